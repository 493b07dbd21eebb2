#include "rl/learner.hpp"

#include <torch/torch.h>

#include <dlfcn.h>

#include <optional>
#include <sstream>

#include "common/resources.hpp"
#include "rl/replay_buffer.hpp"

namespace comorph::rl {

std::string rl_config_dir() { return resource_path("configs/rl"); }

void check_device_name(const std::string& name) {
  std::optional<torch::Device> device;
  try {
    device.emplace(name);
  } catch (const std::exception&) {
    throw std::invalid_argument("unknown torch device \"" + quote_value(name) + "\" (use cpu, cuda, cuda:N)");
  }
  if (device->is_cuda()) {
    if (!torch::cuda::is_available())
      throw std::invalid_argument("torch device \"" + name + "\" is not available: this LibTorch or machine has "
                                  "no CUDA device (use cpu)");
    const auto count = static_cast<int>(torch::cuda::device_count());
    if (device->has_index() && device->index() >= count)
      throw std::invalid_argument("torch device \"" + name + "\" is not available: " + std::to_string(count) +
                                  " CUDA device(s) here");
  } else if (!device->is_cpu()) {
    throw std::invalid_argument("torch device \"" + name + "\" is not supported (use cpu, cuda, cuda:N)");
  }
}

void set_torch_threads(int intra_op_threads, int inter_op_threads) {
  if (intra_op_threads > 0) {
    at::set_num_threads(intra_op_threads);
    // Debian's libtorch runs its matrix products in OpenBLAS (pthread build),
    // whose own pool ignores torch's setting and defaults to one thread per
    // core: on a shared 2-core machine that oversubscribes badly. Set it too,
    // when OpenBLAS is the BLAS in this process.
    using SetThreads = void (*)(int);
    if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")))
      set(intra_op_threads);
  }
  static bool inter_op_set = false;
  if (inter_op_threads > 0 && !inter_op_set) {
    try {
      at::set_num_interop_threads(inter_op_threads);
    } catch (const std::exception&) {
      // Already started (the pool is created on first use): keep it.
    }
    inter_op_set = true;
  }
}

std::string rng_state(const std::mt19937_64& rng) {
  std::ostringstream out;
  out << rng;
  return out.str();
}

void set_rng_state(std::mt19937_64& rng, const std::string& state) {
  std::istringstream in(state);
  in >> rng;
  if (!in) throw std::runtime_error("checkpoint: corrupt RNG state");
}

void write_common(torch::serialize::OutputArchive& a, const LearnerCounters& c,
                  const std::mt19937_64& rng, const std::string& algorithm) {
  a.write("algorithm", c10::IValue(algorithm));
  a.write("counters", torch::tensor({c.transitions, c.episodes, c.updates}));
  a.write("rng", c10::IValue(rng_state(rng)));
}

void save_policy_file(const std::string& path, const torch::nn::Module& networks, const std::string& key,
                      const LearnerCounters& counters, const std::mt19937_64& rng, const std::string& algorithm) {
  torch::serialize::OutputArchive a, nets;
  write_common(a, counters, rng, algorithm);
  a.write("policy_only", c10::IValue(true));
  networks.save(nets);
  a.write(key, nets);
  save_archive(a, path);
}

bool read_policy_only(torch::serialize::InputArchive& a, const std::string& key, torch::nn::Module& networks) {
  c10::IValue flag;
  if (!a.try_read("policy_only", flag) || !flag.toBool()) return false;
  torch::serialize::InputArchive nets;
  a.read(key, nets);
  networks.load(nets);
  return true;
}

void write_replay(torch::serialize::OutputArchive& a, const ReplayBuffer& replay, bool with_replay) {
  if (!with_replay) {
    a.write("replay_elsewhere", c10::IValue(true));
    return;
  }
  torch::serialize::OutputArchive r;
  replay.save(r);
  a.write("replay", r);
}

void read_replay(torch::serialize::InputArchive& a, ReplayBuffer& replay) {
  c10::IValue elsewhere;
  if (a.try_read("replay_elsewhere", elsewhere) && elsewhere.toBool()) return;
  torch::serialize::InputArchive r;
  a.read("replay", r);
  replay.load(r);
}

void read_common(torch::serialize::InputArchive& a, LearnerCounters& c, std::mt19937_64& rng,
                 const std::string& algorithm) {
  c10::IValue name;
  a.read("algorithm", name);
  if (name.toStringRef() != algorithm)
    throw std::runtime_error("checkpoint holds a " + name.toStringRef() + " learner, not " +
                             algorithm);
  torch::Tensor t;
  a.read("counters", t);
  t = t.to(torch::kCPU);  // the archive may have been mapped to a GPU
  const auto* v = t.data_ptr<std::int64_t>();
  c.transitions = v[0];
  c.episodes = v[1];
  c.updates = v[2];
  c10::IValue state;
  a.read("rng", state);
  set_rng_state(rng, state.toStringRef());
}

}  // namespace comorph::rl
