// Robot configuration C = {C_a, C_s} of a chain-type modular robot (paper
// Sec. II-A, Fig. 1). No MuJoCo, no torch: this layer is plain data.
//
// Conventions (1-based module numbers, as in the paper):
// - C_a (10x10, 0/1): C_a(i, j) = 1 when module i and module j are connected.
// - C_s (10x5): one row per connection, (module_i, module_j, face_i, face_j,
//   connection); an all-zero row is unused. face 1 is the front plate, face 2
//   the back plate; connection 1 means the magnetic faces are attached.
// - A chain of N modules uses modules 1..N; module i's back face (2) docks to
//   module i+1's front face (1); module 1's front face is never connected.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace comorph {

// The module limits of the whole project (sim, control, task and the
// configuration model read them from here).
inline constexpr int kMaxModules = 10;
inline constexpr int kMinModules = 2;  // one module cannot climb (paper Sec. III-A)
inline constexpr int kConnectionColumns = 5;
inline constexpr int kFrontFace = 1;
inline constexpr int kBackFace = 2;

using AdjacencyMatrix = std::array<std::array<int, kMaxModules>, kMaxModules>;
using ConnectionMatrix = std::array<std::array<int, kConnectionColumns>, kMaxModules>;

struct Configuration {
  AdjacencyMatrix C_a{};   // zero-initialised
  ConnectionMatrix C_s{};  // zero-initialised
};
inline bool operator==(const Configuration& a, const Configuration& b) {
  return a.C_a == b.C_a && a.C_s == b.C_s;
}
inline bool operator!=(const Configuration& a, const Configuration& b) { return !(a == b); }

// The chain of `modules` modules (kMinModules..kMaxModules); throws
// std::invalid_argument outside that range.
Configuration make_chain(int modules);

// Empty string when valid; otherwise a message that names the first fault
// (asymmetric C_a, self-connection, loop, disconnected module, face used twice,
// out-of-range index, C_a and C_s disagreeing, not a chain of
// kMinModules..kMaxModules modules).
std::string validate(const Configuration& config);

// Empty string when `part` is what `whole` becomes by shedding modules: `part`
// is valid, has fewer modules, and each of its connections is one of `whole`'s
// (the same modules at the same faces). Otherwise names the first fault.
std::string validate_sub_configuration(const Configuration& whole, const Configuration& part);

// The module docked to face `face` of module `module` (1-based) through a
// connected C_s row, 0 when that face is free.
int module_at_face(const Configuration& config, int module, int face);

// Number of modules of a valid configuration; throws std::invalid_argument with
// validate()'s message when the configuration is not valid.
int module_count(const Configuration& config);

// C_s rows of the chain whose adjacency is `C_a` (rows ordered by module_i);
// C_a is not validated here.
ConnectionMatrix connections_from_adjacency(const AdjacencyMatrix& C_a);

// C_a implied by the connected rows of `C_s` (indices outside 1..kMaxModules ignored).
AdjacencyMatrix adjacency_from_connections(const ConnectionMatrix& C_s);

// A short human-readable form, e.g. "chain of 4 modules: 1-2-3-4".
std::string describe(const Configuration& config);

// ---- YAML (configuration_yaml.cpp) ----
// File layout:
//   C_a: [[0,1,0,...], ...]   # 10 rows of 10
//   C_s: [[1,2,2,1,1], ...]   # up to 10 rows of 5 (missing rows are zero)
// or the shorthand `modules: N` for a chain of N.
// Loading errors throw std::runtime_error naming the file and the field.
Configuration load_configuration(const std::string& path);
void save_configuration(const std::string& path, const Configuration& config);
std::string to_yaml(const Configuration& config);
Configuration configuration_from_yaml(const std::string& text,
                                      const std::string& source_name = "<string>");

}  // namespace comorph
