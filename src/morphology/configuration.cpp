#include "morphology/configuration.hpp"

#include <numeric>
#include <sstream>
#include <stdexcept>

namespace comorph {
namespace {

bool row_is_empty(const std::array<int, kConnectionColumns>& row) {
  for (int v : row)
    if (v != 0) return false;
  return true;
}

// Union-find over module numbers 1..kMaxModules (index 0 unused).
struct DisjointSets {
  std::array<int, kMaxModules + 1> parent{};
  DisjointSets() { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  bool join(int a, int b) {  // false when a and b were already joined
    a = find(a);
    b = find(b);
    if (a == b) return false;
    parent[b] = a;
    return true;
  }
};

std::string fault(const std::ostringstream& message) { return message.str(); }

}  // namespace

Configuration make_chain(int modules) {
  if (modules < kMinModules || modules > kMaxModules)
    throw std::invalid_argument("a chain needs " + std::to_string(kMinModules) + ".." +
                                std::to_string(kMaxModules) + " modules, got " +
                                std::to_string(modules));
  Configuration config;
  for (int i = 1; i < modules; ++i) {
    config.C_a[i - 1][i] = config.C_a[i][i - 1] = 1;
    config.C_s[i - 1] = {i, i + 1, kBackFace, kFrontFace, 1};
  }
  return config;
}

std::string validate(const Configuration& config) {
  const auto& C_a = config.C_a;
  const auto& C_s = config.C_s;
  std::ostringstream m;

  // C_a on its own: 0/1 entries, no self-connection, symmetric.
  for (int i = 0; i < kMaxModules; ++i) {
    for (int j = 0; j < kMaxModules; ++j) {
      if (C_a[i][j] != 0 && C_a[i][j] != 1) {
        m << "C_a(" << i + 1 << "," << j + 1 << ") = " << C_a[i][j] << " is not 0 or 1";
        return fault(m);
      }
    }
    if (C_a[i][i] != 0) {
      m << "C_a(" << i + 1 << "," << i + 1 << ") = 1: module " << i + 1
        << " is connected to itself";
      return fault(m);
    }
  }
  for (int i = 0; i < kMaxModules; ++i)
    for (int j = i + 1; j < kMaxModules; ++j)
      if (C_a[i][j] != C_a[j][i]) {
        m << "C_a is not symmetric: C_a(" << i + 1 << "," << j + 1 << ") = " << C_a[i][j]
          << " but C_a(" << j + 1 << "," << i + 1 << ") = " << C_a[j][i];
        return fault(m);
      }

  // C_s rows on their own: indices in range, faces used once.
  std::array<std::array<int, 3>, kMaxModules + 1> face_row{};  // [module][face] -> row+1
  for (int r = 0; r < kMaxModules; ++r) {
    const auto& row = C_s[r];
    if (row_is_empty(row)) continue;
    const int mi = row[0], mj = row[1], fi = row[2], fj = row[3], connected = row[4];
    for (int k = 0; k < 2; ++k)
      if (row[k] < 1 || row[k] > kMaxModules) {
        m << "C_s row " << r + 1 << ": " << (k == 0 ? "module_i" : "module_j") << " = "
          << row[k] << " is out of range 1.." << kMaxModules;
        return fault(m);
      }
    for (int k = 2; k < 4; ++k)
      if (row[k] != kFrontFace && row[k] != kBackFace) {
        m << "C_s row " << r + 1 << ": " << (k == 2 ? "face_i" : "face_j") << " = " << row[k]
          << " is out of range (1 = front, 2 = back)";
        return fault(m);
      }
    if (connected != 0 && connected != 1) {
      m << "C_s row " << r + 1 << ": connection = " << connected << " is not 0 or 1";
      return fault(m);
    }
    if (mi == mj) {
      m << "C_s row " << r + 1 << ": module " << mi << " is connected to itself";
      return fault(m);
    }
    if (!connected) continue;
    for (auto [module, face] : {std::pair{mi, fi}, std::pair{mj, fj}}) {
      if (face_row[module][face] != 0) {
        m << "face " << face << " of module " << module << " is used twice (C_s rows "
          << face_row[module][face] << " and " << r + 1 << ")";
        return fault(m);
      }
      face_row[module][face] = r + 1;
    }
  }
  if (face_row[1][kFrontFace] != 0) {
    m << "module 1's front face (face 1) is connected (C_s row " << face_row[1][kFrontFace]
      << "); it must stay free";
    return fault(m);
  }

  // C_a and C_s must describe the same connections.
  const AdjacencyMatrix from_rows = adjacency_from_connections(C_s);
  for (int i = 0; i < kMaxModules; ++i)
    for (int j = i + 1; j < kMaxModules; ++j)
      if (from_rows[i][j] != C_a[i][j]) {
        m << "C_a and C_s disagree: C_a(" << i + 1 << "," << j + 1 << ") = " << C_a[i][j]
          << " but C_s " << (from_rows[i][j] ? "connects" : "has no connection between")
          << " modules " << i + 1 << " and " << j + 1;
        return fault(m);
      }

  // The graph: a tree containing module 1, no loops, no stray modules.
  DisjointSets sets;
  std::array<bool, kMaxModules + 1> present{};
  int edges = 0;
  for (int i = 1; i <= kMaxModules; ++i)
    for (int j = i + 1; j <= kMaxModules; ++j) {
      if (!C_a[i - 1][j - 1]) continue;
      present[i] = present[j] = true;
      ++edges;
      if (!sets.join(i, j)) {
        m << "the connections form a loop (closed by modules " << i << " and " << j << ")";
        return fault(m);
      }
    }
  if (edges == 0) return "no connections: a robot needs at least 2 connected modules";
  if (!present[1]) return "module 1 (the head, with the camera) is not connected";
  for (int k = 2; k <= kMaxModules; ++k)
    if (present[k] && sets.find(k) != sets.find(1)) {
      m << "module " << k << " is disconnected from module 1";
      return fault(m);
    }
  const int modules = edges + 1;  // a tree
  for (int k = 1; k <= kMaxModules; ++k)
    if (present[k] != (k <= modules)) {
      m << "modules must be numbered 1.." << modules << " along the chain, but module " << k
        << (present[k] ? " is used" : " is missing");
      return fault(m);
    }

  // Chain order: module i's back face to module i+1's front face.
  for (int r = 0; r < kMaxModules; ++r) {
    const auto& row = C_s[r];
    if (row_is_empty(row) || !row[4]) continue;
    const bool forward = row[1] == row[0] + 1 && row[2] == kBackFace && row[3] == kFrontFace;
    const bool backward = row[0] == row[1] + 1 && row[2] == kFrontFace && row[3] == kBackFace;
    if (!forward && !backward) {
      m << "C_s row " << r + 1 << " (" << row[0] << "," << row[1] << "," << row[2] << ","
        << row[3] << "," << row[4] << ") is not a chain link: module i's back face (2) must "
        << "dock to module i+1's front face (1)";
      return fault(m);
    }
  }
  return {};
}

int module_at_face(const Configuration& config, int module, int face) {
  for (const auto& row : config.C_s) {
    if (row[4] != 1) continue;
    if (row[0] == module && row[2] == face) return row[1];
    if (row[1] == module && row[3] == face) return row[0];
  }
  return 0;
}

std::string validate_sub_configuration(const Configuration& whole, const Configuration& part) {
  if (std::string error = validate(whole); !error.empty()) return "the current configuration is invalid: " + error;
  if (std::string error = validate(part); !error.empty()) return "the new configuration is invalid: " + error;
  const int kept = module_count(part), had = module_count(whole);
  if (kept >= had)
    return "only shedding modules is possible: " + std::to_string(had) + " -> " + std::to_string(kept) +
           " modules sheds none";
  for (const auto& row : part.C_s) {
    if (row[4] != 1) continue;
    const int mi = row[0], mj = row[1], fi = row[2], fj = row[3];
    if (module_at_face(whole, mi, fi) != mj || module_at_face(whole, mj, fj) != mi) {
      std::ostringstream m;
      m << "module " << mi << " face " << fi << " to module " << mj << " face " << fj
        << " is not a connection of the current configuration";
      return fault(m);
    }
  }
  return {};
}

int module_count(const Configuration& config) {
  if (std::string error = validate(config); !error.empty())
    throw std::invalid_argument("invalid configuration: " + error);
  int edges = 0;
  for (int i = 0; i < kMaxModules; ++i)
    for (int j = i + 1; j < kMaxModules; ++j) edges += config.C_a[i][j];
  return edges + 1;
}

ConnectionMatrix connections_from_adjacency(const AdjacencyMatrix& C_a) {
  ConnectionMatrix C_s{};
  int row = 0;
  for (int i = 0; i < kMaxModules && row < kMaxModules; ++i)
    for (int j = i + 1; j < kMaxModules && row < kMaxModules; ++j)
      if (C_a[i][j]) C_s[row++] = {i + 1, j + 1, kBackFace, kFrontFace, 1};
  return C_s;
}

AdjacencyMatrix adjacency_from_connections(const ConnectionMatrix& C_s) {
  AdjacencyMatrix C_a{};
  for (const auto& row : C_s) {
    const int i = row[0], j = row[1];
    if (row[4] != 1 || i < 1 || j < 1 || i > kMaxModules || j > kMaxModules || i == j) continue;
    C_a[i - 1][j - 1] = C_a[j - 1][i - 1] = 1;
  }
  return C_a;
}

std::string describe(const Configuration& config) {
  if (std::string error = validate(config); !error.empty()) return "invalid (" + error + ")";
  const int n = module_count(config);
  std::string text = "chain of " + std::to_string(n) + " modules: 1";
  for (int k = 2; k <= n; ++k) text += "-" + std::to_string(k);
  return text;
}

}  // namespace comorph
