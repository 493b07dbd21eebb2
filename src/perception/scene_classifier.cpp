// SceneClassifier: inference, save and load (scene_classifier.hpp).
#include "perception/scene_classifier.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <stdexcept>

#include "common/torch_archive.hpp"
#include "common/yaml_fields.hpp"  // load_yaml_file, write_file_atomic
#include "perception/scene_classifier_impl.hpp"

namespace comorph::perception {
namespace {

constexpr const char* kWeightsFile = "classifier.pt";
constexpr const char* kSidecarFile = "classifier.yaml";
constexpr const char* kFormat = "comorph-scene-classifier";
constexpr int kFormatVersion = 1;

void check_params(const ClassifierParams& p) {
  const std::string err = p.validate();
  if (!err.empty()) throw std::invalid_argument("classifier parameters: " + err);
}

ClassifierParams read_sidecar(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error(path + ": cannot open the classifier sidecar (is the directory a "
                                    "saved classifier?)");
  const YAML::Node root = load_yaml_file(path);
  auto field = [&](const char* key) {
    if (!root.IsMap() || !root[key]) throw std::runtime_error(path + ": missing field '" + key + "'");
    return root[key];
  };
  try {
    if (field("format").as<std::string>() != kFormat)
      throw std::runtime_error(path + ": field 'format' is not " + kFormat);
    const int version = field("version").as<int>();
    if (version != kFormatVersion)
      throw std::runtime_error(path + ": unsupported version " + std::to_string(version));
    ClassifierParams p;
    p.image_size = field("image_size").as<int>();
    p.classes = field("classes").as<int>();
    p.width = field("width").as<int>();
    p.class_names = field("class_names").as<std::vector<std::string>>();
    const std::string err = p.validate();
    if (!err.empty()) throw std::runtime_error(path + ": " + err);
    return p;
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": bad field value: " + e.msg);
  }
}

void check_expected(const std::string& path, const ClassifierParams& got,
                    const ClassifierParams& want) {
  auto mismatch = [&](const char* field, int g, int w) {
    if (g != w)
      throw std::runtime_error(path + ": " + field + " " + std::to_string(g) +
                               " does not match the expected " + std::to_string(w) +
                               " (the model was trained for other settings)");
  };
  mismatch("image_size", got.image_size, want.image_size);
  mismatch("classes", got.classes, want.classes);
  mismatch("width", got.width, want.width);
}

torch::Tensor input_tensor(const SceneClassifier::Impl& m, const float* depths, int n, int h, int w) {
  if (n < 1) throw std::invalid_argument("SceneClassifier: need at least one image");
  if (h != m.params.image_size || w != m.params.image_size)
    throw std::invalid_argument("SceneClassifier: image is " + std::to_string(h) + "x" +
                                std::to_string(w) + " pixels, the model expects " +
                                std::to_string(m.params.image_size) + "x" +
                                std::to_string(m.params.image_size));
  // from_blob does not copy; to() copies only when the device is not the CPU.
  return torch::from_blob(const_cast<float*>(depths), {n, 1, h, w}, torch::kFloat32).to(m.device);
}

}  // namespace

torch::Device parse_device(const std::string& device) {
  std::optional<torch::Device> d;
  try {
    d.emplace(device);
  } catch (const c10::Error&) {
    throw std::invalid_argument("unknown torch device '" + quote_value(device) + "' (cpu, cuda, cuda:N)");
  }
  // Here, not at the first forward pass deep inside LibTorch.
  if (d->is_cuda() && (!torch::cuda::is_available() || (d->has_index() && static_cast<std::size_t>(d->index()) >= torch::cuda::device_count())))
    throw std::invalid_argument("torch device '" + device + "' is not available here (use cpu)");
  return *d;
}

SceneClassifier::SceneClassifier(const ClassifierParams& params, std::uint64_t seed) {
  check_params(params);
  // Initialise from `seed` without disturbing the global generator that
  // other torch users (the RL learners) draw from.
  auto generator = at::detail::getDefaultCPUGenerator();
  const torch::Tensor saved = generator.get_state();
  generator.set_current_seed(seed);
  try {
    impl_ = std::make_unique<Impl>(params, parse_device(params.device));
  } catch (...) {
    generator.set_state(saved);
    throw;
  }
  generator.set_state(saved);
  impl_->net->eval();
}

SceneClassifier::SceneClassifier(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SceneClassifier::~SceneClassifier() = default;
SceneClassifier::SceneClassifier(SceneClassifier&&) noexcept = default;
SceneClassifier& SceneClassifier::operator=(SceneClassifier&&) noexcept = default;

const ClassifierParams& SceneClassifier::params() const { return impl_->params; }

void SceneClassifier::set_threads(int threads) {
  if (threads < 1) throw std::invalid_argument("threads must be >= 1");
  at::set_num_threads(threads);
}

std::int64_t SceneClassifier::parameter_count() const {
  std::int64_t n = 0;
  for (const auto& p : impl_->net->parameters()) n += p.numel();
  return n;
}

std::vector<float> SceneClassifier::flat_parameters() const {
  std::vector<float> out;
  auto append = [&](const torch::Tensor& t) {
    const torch::Tensor c = t.detach().to(torch::kCPU, torch::kFloat32).contiguous();
    out.insert(out.end(), c.data_ptr<float>(), c.data_ptr<float>() + c.numel());
  };
  for (const auto& p : impl_->net->parameters()) append(p);
  for (const auto& b : impl_->net->buffers()) append(b);
  return out;
}

void SceneClassifier::logits(const float* depths, int n, int h, int w, float* out) {
  torch::InferenceMode guard;
  Impl& m = *impl_;
  if (m.net->is_training()) m.net->eval();
  const torch::Tensor y = m.net->forward(input_tensor(m, depths, n, h, w)).to(torch::kCPU).contiguous();
  std::copy(y.data_ptr<float>(), y.data_ptr<float>() + y.numel(), out);
}

void SceneClassifier::classify_batch(const float* depths, int n, int h, int w, int* labels) {
  torch::InferenceMode guard;
  Impl& m = *impl_;
  if (m.net->is_training()) m.net->eval();
  const torch::Tensor best =
      m.net->forward(input_tensor(m, depths, n, h, w)).argmax(1).to(torch::kCPU).contiguous();
  const std::int64_t* b = best.data_ptr<std::int64_t>();
  for (int i = 0; i < n; ++i) labels[i] = static_cast<int>(b[i]);
}

int SceneClassifier::classify(const float* depth, int h, int w) {
  int label = 0;
  classify_batch(depth, 1, h, w, &label);
  return label;
}

void SceneClassifier::save(const std::string& dir) const {
  namespace fs = std::filesystem;
  const Impl& m = *impl_;
  fs::create_directories(dir);
  const fs::path weights = fs::path(dir) / kWeightsFile;
  const fs::path tmp = weights.string() + ".tmp";
  torch::serialize::OutputArchive archive;
  m.net->save(archive);  // what torch::save(m.net, ...) writes, through a checked writer
  save_archive(archive, tmp.string());
  fs::rename(tmp, weights);

  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "format" << YAML::Value << kFormat;
  y << YAML::Key << "version" << YAML::Value << kFormatVersion;
  y << YAML::Key << "architecture" << YAML::Value
    << "resnet18 (BasicBlock 2-2-2-2, batch norm, 1-channel 3x3 stride-1 stem, no max-pool)";
  y << YAML::Key << "image_size" << YAML::Value << m.params.image_size;
  y << YAML::Key << "classes" << YAML::Value << m.params.classes;
  y << YAML::Key << "class_names" << YAML::Value << YAML::Flow << m.params.class_names;
  y << YAML::Key << "width" << YAML::Value << m.params.width;
  y << YAML::Key << "input" << YAML::Value << "depth, 1 x image_size x image_size, in [0.01, 1]";
  y << YAML::EndMap;
  write_file_atomic((fs::path(dir) / kSidecarFile).string(), std::string(y.c_str()) + "\n");
}

SceneClassifier SceneClassifier::load(const std::string& dir, const ClassifierParams* expected,
                                      const std::string& device) {
  namespace fs = std::filesystem;
  const std::string sidecar = (fs::path(dir) / kSidecarFile).string();
  const std::string weights = (fs::path(dir) / kWeightsFile).string();
  ClassifierParams p = read_sidecar(sidecar);
  if (expected) check_expected(sidecar, p, *expected);
  p.device = !device.empty() ? device : expected ? expected->device : "cpu";
  auto impl = std::make_unique<Impl>(p, parse_device(p.device));

  // torch::load replaces tensors whatever their shape, so check the shapes.
  std::map<std::string, std::vector<std::int64_t>> shapes;
  for (const auto& t : impl->net->named_parameters()) shapes[t.key()] = t.value().sizes().vec();
  for (const auto& t : impl->net->named_buffers()) shapes[t.key()] = t.value().sizes().vec();
  if (!fs::exists(weights)) throw std::runtime_error(weights + ": missing weights file");
  try {
    torch::load(impl->net, weights, impl->device);
  } catch (const c10::Error& e) {
    const std::string what = e.what_without_backtrace();
    throw std::runtime_error(weights + ": weights do not fit the net described by " + sidecar +
                             ": " + what.substr(0, what.find('\n')));
  }
  auto check = [&](const std::string& name, const torch::Tensor& t) {
    if (t.sizes().vec() != shapes[name])
      throw std::runtime_error(weights + ": tensor '" + name + "' has shape " +
                               c10::str(t.sizes()) + " but the net described by " + sidecar +
                               " (width " + std::to_string(p.width) + ", classes " +
                               std::to_string(p.classes) + ") needs " +
                               c10::str(c10::IntArrayRef(shapes[name])));
  };
  for (const auto& t : impl->net->named_parameters()) check(t.key(), t.value());
  for (const auto& t : impl->net->named_buffers()) check(t.key(), t.value());
  impl->net->to(impl->device);
  impl->net->eval();
  return SceneClassifier(std::move(impl));
}

}  // namespace comorph::perception
