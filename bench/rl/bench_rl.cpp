// bench_rl: how fast the learners of src/rl update and act on this machine.
//
// For each update it prints the time per update, the floating-point work it
// does (counted from the layer sizes: forward 2*in*out per sample and layer,
// backward twice that; Adam and element-wise ops not counted), and the time the
// same work takes in a bare loop of 256x256x256 float matrix products
// (at::mm_out into a preallocated result). ratio = update time / matmul time:
// 1 would be the hardware's matmul speed; the excess is framework overhead,
// convolution and small-op cost.
//
// Threads: torch's intra-op pool is set with --threads (default 1; the
// comparison at 1 and 2 threads is printed) and the inter-op pool to 1.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <torch/torch.h>

#include <chrono>
#include <functional>
#include <random>

#include "rl/dqn.hpp"
#include "rl/flat_adam.hpp"
#include "rl/learner.hpp"
#include "rl/sac.hpp"
#include "rl/td3.hpp"

namespace rl = comorph::rl;

namespace {

double seconds_per_call(const std::function<void()>& f, double min_seconds) {
  f();  // warm-up (allocator, first-touch)
  int calls = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed = 0;
  do {
    f();
    ++calls;
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  } while (elapsed < min_seconds);
  return elapsed / calls;
}

// Seconds per floating-point operation in a bare matmul loop.
double matmul_seconds_per_flop(double min_seconds) {
  const torch::Tensor a = torch::rand({256, 256}), b = torch::rand({256, 256});
  torch::Tensor c = torch::empty({256, 256});
  const double t = seconds_per_call([&] { at::mm_out(c, a, b); }, min_seconds);
  return t / (2.0 * 256 * 256 * 256);
}

rl::Observation random_observation(const rl::ObservationSpec& spec, std::mt19937_64& rng) {
  rl::Observation o;
  rl::allocate(spec, o);
  std::uniform_real_distribution<float> u(0.01f, 1.0f);
  for (float& v : o.image) v = u(rng);
  for (float& v : o.vector) v = u(rng);
  return o;
}

template <typename L>
void fill(L& learner, const rl::ObservationSpec& spec, rl::ActionSpec action, int n) {
  std::mt19937_64 rng(1);
  rl::Action a;
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < n; ++i) {
    const rl::Observation o = random_observation(spec, rng), next = random_observation(spec, rng);
    if (action.kind == rl::ActionKind::kDiscrete) {
      a.discrete = i % action.size;
    } else {
      a.continuous.resize(action.size);
      for (float& v : a.continuous) v = u(rng);
    }
    learner.store(o, a, u(rng), next, i % 200 == 199, false);
  }
}

struct Row {
  std::string name;
  double seconds;  // per update
  double flops;    // per update
};

void print_row(const Row& r, double matmul_s_per_flop) {
  const double matmul_s = r.flops * matmul_s_per_flop;
  fmt::print("{:<46} {:>10.3f} ms {:>9.1f} /s {:>9.1f} MFLOP {:>9.3f} ms {:>7.2f}\n", r.name,
             r.seconds * 1e3, 1.0 / r.seconds, r.flops / 1e6, matmul_s * 1e3, r.seconds / matmul_s);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_rl: update rates and acting latency of the RL core"};
  int image_size = 16, vector_size = 45, action_dims = 5, batch = 256, threads = 1;
  double min_seconds = 2.0;
  app.add_option("--image-size", image_size, "depth image side, pixels")->capture_default_str();
  app.add_option("--vector-size", vector_size, "robot-state vector length")->capture_default_str();
  app.add_option("--batch", batch, "update batch size")->capture_default_str();
  app.add_option("--action-dims", action_dims, "continuous action dimensions")->capture_default_str();
  app.add_option("--threads", threads, "torch intra-op threads")->capture_default_str();
  app.add_option("--min-seconds", min_seconds, "time per measurement, s")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  rl::set_torch_threads(threads, 1);

  fmt::print("torch {} intra-op thread(s), {} inter-op; batch {}, MLPs 256 wide unless named, image 1x{}x{}, "
             "vector {}, action {}\n",
             at::get_num_threads(), at::get_num_interop_threads(), batch, image_size, image_size,
             vector_size, action_dims);
  const double s_per_flop = matmul_seconds_per_flop(min_seconds);
  fmt::print("bare matmul loop (256x256x256 float): {:.2f} GFLOP/s\n\n", 1e-9 / s_per_flop);
  fmt::print("{:<46} {:>13} {:>12} {:>15} {:>12} {:>7}\n", "update", "time", "rate", "work",
             "matmul time", "ratio");

  const rl::ObservationSpec vec_spec{0, 0, 0, vector_size};
  const rl::ObservationSpec img_spec{1, image_size, image_size, vector_size};
  const rl::ActionSpec cont{rl::ActionKind::kContinuous, action_dims};

  // TD3 (vector observation) at three widths: the smaller the networks, the
  // larger the share of per-operation overhead (ratio) in an update. Each
  // width twice: the explicit passes the learner takes (rl/mlp_pass.hpp) and
  // autograd, which computes the same numbers.
  for (int width : {64, 128, 256}) {
    for (const bool autograd : {false, true}) {
      rl::Td3Config c;
      c.batch_size = batch;
      c.hidden_sizes = {width, width};
      rl::Td3 td3(vec_spec, action_dims, c, 1);
      td3.force_autograd(autograd);
      fill(td3, vec_spec, cont, 2000);
      const double Fa = td3.networks()->actor->forward_flops();
      const double Fc = td3.networks()->critic1->forward_flops();
      // target actor + 2 target critics; 2 critics fwd+bwd; actor step (actor fwd+bwd,
      // critic fwd+bwd) every policy_delay updates.
      const double flops = batch * (Fa + 2 * Fc + 6 * Fc + (3 * Fa + 3 * Fc) / c.policy_delay);
      print_row({fmt::format("TD3 update (vector obs), {} wide, {}", width, autograd ? "autograd" : "explicit"),
                 seconds_per_call([&] { td3.update(); }, min_seconds), flops},
                s_per_flop);
    }
  }
  // SAC (vector observation).
  {
    rl::SacConfig c;
    c.batch_size = batch;
    c.hidden_sizes = {256, 256};
    rl::Sac sac(vec_spec, action_dims, c, 1);
    fill(sac, vec_spec, cont, 2000);
    const double Fa = sac.networks()->actor->forward_flops();
    const double Fc = sac.networks()->critic1->forward_flops();
    // next-action sample + 2 target critics; 2 critics fwd+bwd; policy_frequency actor
    // steps (actor fwd+bwd, 2 critics fwd+bwd) every policy_frequency updates.
    const double flops = batch * (Fa + 2 * Fc + 6 * Fc + 3 * Fa + 6 * Fc);
    print_row({"SAC update (vector obs)", seconds_per_call([&] { sac.update(); }, min_seconds), flops},
              s_per_flop);
  }
  // The paper encoder alone: forward + backward + Adam at batch `batch`.
  {
    rl::CnnEncoder enc(1, image_size, image_size, 16);
    torch::optim::Adam opt(enc->parameters(), torch::optim::AdamOptions(1e-4));
    const torch::Tensor x = torch::rand({batch, 1, image_size, image_size});
    const double t = seconds_per_call(
        [&] {
          opt.zero_grad();
          enc->forward(x).pow(2).mean().backward();
          opt.step();
        },
        min_seconds);
    print_row({fmt::format("paper encoder {}x{} fwd+bwd+Adam", image_size, image_size), t,
               3.0 * batch * enc->forward_flops()},
              s_per_flop);
  }
  // TD3 with image + vector: shared encoder (one conv pass for both critics,
  // one for the targets) vs a separate actor encoder.
  for (bool shared : {true, false}) {
    rl::Td3Config c;
    c.batch_size = batch;
    c.hidden_sizes = {256, 256};
    c.share_encoder = shared;
    rl::Td3 td3(img_spec, action_dims, c, 1);
    fill(td3, img_spec, cont, 2000);
    const double Fe = td3.networks()->critic_encoder->forward_flops();
    const double Fa = td3.networks()->actor->forward_flops();
    const double Fc = td3.networks()->critic1->forward_flops();
    double flops = batch * (Fe + Fa + 2 * Fc + 3 * Fe + 6 * Fc + (3 * Fa + 3 * Fc) / c.policy_delay);
    if (!shared) flops += batch * (Fe + 3 * Fe / c.policy_delay);  // target + online actor encoder
    print_row({fmt::format("TD3 update, image+vector, {} encoder", shared ? "shared" : "separate"),
               seconds_per_call([&] { td3.update(); }, min_seconds), flops},
              s_per_flop);
  }
  // The paper's DQN (image only).
  {
    rl::DqnConfig c;
    c.batch_size = 64;
    c.hidden_sizes = {};
    const rl::ObservationSpec spec{1, image_size, image_size, 0};
    rl::Dqn dqn(spec, 9, c, 1);
    fill(dqn, spec, {rl::ActionKind::kDiscrete, 9}, 500);
    rl::CnnEncoder probe(1, image_size, image_size, 9);
    print_row({"paper DQN update (image only, batch 64)",
               seconds_per_call([&] { dqn.update(); }, min_seconds), 64 * 4.0 * probe->forward_flops()},
              s_per_flop);
  }

  // What the flat buffers buy (rl/flat_adam.hpp): the optimizer-side steps of
  // one update over a 64-wide TD3's critic parameters, per tensor as torch
  // does them against one operation over the flat buffer, measured together.
  {
    const auto critic_net = [&] {
      return rl::ActorCritic(vec_spec, action_dims, action_dims, std::vector<int>{64, 64}, 16, 256, true);
    };
    rl::ActorCritic per_tensor = critic_net(), flat = critic_net(), per_tensor_target = critic_net(),
                    flat_target = critic_net();
    const torch::Tensor x = torch::rand({batch, vector_size + action_dims});
    const auto backward = [&](rl::ActorCritic& n) { n->critic1->forward(x).sum().add(n->critic2->forward(x).sum()).backward(); };
    torch::optim::Adam torch_adam(per_tensor->critic_parameters(), torch::optim::AdamOptions(1e-3));
    rl::FlatAdam flat_adam(flat->critic_parameters(), {});
    rl::FlatParameters flat_target_params(flat_target->critic_parameters(), false);
    backward(per_tensor);
    backward(flat);
    const auto tensors = per_tensor->critic_parameters();
    fmt::print("\n{:<46} {:>13} {:>13} {:>7}\n",
               fmt::format("64-wide TD3 critics, {} tensors", tensors.size()), "per tensor", "flat", "ratio");
    const auto row = [&](const std::string& name, const std::function<void()>& a, const std::function<void()>& b) {
      const double ta = seconds_per_call(a, min_seconds / 2), tb = seconds_per_call(b, min_seconds / 2);
      fmt::print("{:<46} {:>10.1f} us {:>10.1f} us {:>7.2f}\n", name, 1e6 * ta, 1e6 * tb, ta / tb);
    };
    row("Adam step", [&] { torch_adam.step(); }, [&] { flat_adam.step(); });
    row("zero_grad + clip_grad_norm", [&] {
      torch_adam.zero_grad();
      torch::nn::utils::clip_grad_norm_(tensors, 1.0);
    }, [&] {
      flat_adam.zero_grad();
      flat_adam.clip_grad_norm(1.0);
    });
    row("Polyak step of the target", [&] {
      torch::NoGradGuard no_grad;
      const auto d = per_tensor_target->critic_parameters();
      for (std::size_t i = 0; i < d.size(); ++i) d[i].mul_(0.995).add_(tensors[i], 0.005);
    }, [&] { rl::soft_update(flat_target_params, flat_adam.parameters(), 0.005); });
  }

  // Acting latency at batch 1 (InferenceMode inside act()).
  fmt::print("\n{:<46} {:>13}\n", "act (batch 1, greedy, InferenceMode)", "latency");
  std::mt19937_64 rng(2);
  rl::Action a;
  {
    rl::Td3Config c;
    rl::Td3 td3(vec_spec, action_dims, c, 1);
    const rl::Observation o = random_observation(vec_spec, rng);
    fmt::print("{:<46} {:>10.1f} us\n", "TD3 actor, vector obs",
               1e6 * seconds_per_call([&] { td3.act(o, false, a); }, min_seconds / 2));
    rl::Td3 td3i(img_spec, action_dims, c, 1);
    const rl::Observation oi = random_observation(img_spec, rng);
    fmt::print("{:<46} {:>10.1f} us\n", fmt::format("TD3 actor, image {}x{} + vector", image_size, image_size),
               1e6 * seconds_per_call([&] { td3i.act(oi, false, a); }, min_seconds / 2));
  }
  {
    rl::SacConfig c;
    c.random_action_steps = 0;  // act with the policy, not the warm-up's uniform actions
    rl::Sac sac(vec_spec, action_dims, c, 1);
    const rl::Observation o = random_observation(vec_spec, rng);
    fmt::print("{:<46} {:>10.1f} us\n", "SAC actor, vector obs (sampled)",
               1e6 * seconds_per_call([&] { sac.act(o, true, a); }, min_seconds / 2));
  }
  {
    rl::DqnConfig c;
    c.hidden_sizes = {};
    const rl::ObservationSpec spec{1, image_size, image_size, 0};
    rl::Dqn dqn(spec, 9, c, 1);
    const rl::Observation o = random_observation(spec, rng);
    fmt::print("{:<46} {:>10.1f} us\n", fmt::format("paper DQN, image {}x{}", image_size, image_size),
               1e6 * seconds_per_call([&] { dqn.act(o, false, a); }, min_seconds / 2));
  }

  // Thread count: the same TD3 update at 1 and 2 intra-op threads.
  fmt::print("\n{:<46} {:>13}\n", "TD3 update (vector obs) vs intra-op threads", "time");
  {
    rl::Td3Config c;
    c.batch_size = batch;
    rl::Td3 td3(vec_spec, action_dims, c, 1);
    fill(td3, vec_spec, cont, 2000);
    for (int n : {1, 2}) {
      rl::set_torch_threads(n, 1);
      fmt::print("{:<46} {:>10.3f} ms\n", fmt::format("{} thread(s)", n),
                 1e3 * seconds_per_call([&] { td3.update(); }, min_seconds));
    }
    rl::set_torch_threads(threads, 1);
  }
  return 0;
}
