// The trainer's learner thread, and the transition it is handed. Internal to coopt.
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

#include "rl/env.hpp"

namespace comorph::coopt {

// The learner thread: runs one job at a time (store + updates of an interval);
// with threaded false, submit() runs the job at once on the calling thread.
class LearnerWorker {
 public:
  explicit LearnerWorker(bool threaded) : threaded_(threaded) {
    if (threaded_) thread_ = std::thread([this] { loop(); });
  }
  ~LearnerWorker() {
    if (!threaded_) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void submit(std::function<void()> job) {
    if (!threaded_) {
      job();
      return;
    }
    wait();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = std::move(job);
      pending_ = true;
    }
    cv_.notify_all();
  }
  void wait() {
    if (!threaded_) return;
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return !pending_; });
    if (error_) {
      auto e = error_;
      error_ = nullptr;
      std::rethrow_exception(e);
    }
  }

 private:
  void loop() {
    while (true) {
      std::function<void()> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return pending_ || quit_; });
        if (quit_ && !pending_) return;
        job = std::move(job_);
      }
      try {
        job();
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        pending_ = false;
      }
      cv_.notify_all();
    }
  }
  bool threaded_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::function<void()> job_;
  bool pending_ = false, quit_ = false;
  std::exception_ptr error_;
};

// A transition as an actor hands it over (also a decision of the
// configuration model kept for the return target).
struct Transition {
  rl::Observation obs, next;
  rl::Action action;
  float reward = 0;
  bool terminated = false, truncated = false;
  int steps = 1;  // control steps it sums (trainer.motion_n_step); its discount is gamma^steps
  // Copies a step into this preallocated one (same sizes: no allocation).
  void set(const rl::Observation& o, const rl::Action& a, float r, const rl::Observation& n, bool term, bool trunc,
           int k = 1) {
    obs.image = o.image;
    obs.vector = o.vector;
    next.image = n.image;
    next.vector = n.vector;
    action.continuous = a.continuous;
    action.target = a.target;
    reward = r;
    terminated = term;
    truncated = trunc;
    steps = k;
  }
};

}  // namespace comorph::coopt
