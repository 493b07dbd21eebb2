#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "morphology/configuration.hpp"

using namespace comorph;

namespace {

// Expects validate() to reject `config` with a message containing `needle`.
void expect_fault(const Configuration& config, const std::string& needle) {
  const std::string error = validate(config);
  ASSERT_FALSE(error.empty()) << "expected a fault containing '" << needle << "'";
  EXPECT_NE(error.find(needle), std::string::npos) << "message was: " << error;
}

void connect(Configuration& c, int i, int j) { c.C_a[i - 1][j - 1] = c.C_a[j - 1][i - 1] = 1; }

}  // namespace

TEST(Configuration, ChainsOfTwoToTenAreValid) {
  for (int n = kMinModules; n <= kMaxModules; ++n) {
    const Configuration c = make_chain(n);
    EXPECT_EQ(validate(c), "") << n;
    EXPECT_EQ(module_count(c), n);
    EXPECT_EQ(c.C_s[0][0], 1);
    EXPECT_EQ(c.C_s[n - 2][1], n);  // last link ends at module n
    for (int r = n - 1; r < kMaxModules; ++r)
      for (int v : c.C_s[r]) EXPECT_EQ(v, 0) << "unused rows are zero";
  }
}

TEST(Configuration, ChainOutOfRangeThrows) {
  EXPECT_THROW(make_chain(1), std::invalid_argument);
  EXPECT_THROW(make_chain(11), std::invalid_argument);
}

TEST(Configuration, ConversionBothWaysRoundTrips) {
  for (int n = kMinModules; n <= kMaxModules; ++n) {
    const Configuration c = make_chain(n);
    EXPECT_EQ(adjacency_from_connections(c.C_s), c.C_a);
    EXPECT_EQ(connections_from_adjacency(c.C_a), c.C_s);
  }
}

TEST(Configuration, PaperFigureOneFourModules) {
  // Fig. 1: four modules, three rows in C_s.
  const Configuration c = make_chain(4);
  EXPECT_EQ(c.C_s[0], (std::array<int, 5>{1, 2, 2, 1, 1}));
  EXPECT_EQ(c.C_s[1], (std::array<int, 5>{2, 3, 2, 1, 1}));
  EXPECT_EQ(c.C_s[2], (std::array<int, 5>{3, 4, 2, 1, 1}));
  EXPECT_EQ(describe(c), "chain of 4 modules: 1-2-3-4");
}

TEST(ConfigurationFaults, NonBinaryAdjacency) {
  Configuration c = make_chain(3);
  c.C_a[0][1] = c.C_a[1][0] = 2;
  expect_fault(c, "is not 0 or 1");
}

TEST(ConfigurationFaults, SelfConnection) {
  Configuration c = make_chain(3);
  c.C_a[2][2] = 1;
  expect_fault(c, "connected to itself");
  Configuration d = make_chain(3);
  d.C_s[1] = {2, 2, 2, 1, 1};
  expect_fault(d, "connected to itself");
}

TEST(ConfigurationFaults, AsymmetricAdjacency) {
  Configuration c = make_chain(3);
  c.C_a[1][2] = 0;  // C_a(2,3) = 0 but C_a(3,2) = 1
  expect_fault(c, "not symmetric");
}

TEST(ConfigurationFaults, Loop) {
  // A ring 2-3-4-2 uses every face once, so only the loop check can catch it.
  Configuration c;
  connect(c, 2, 3);
  connect(c, 3, 4);
  connect(c, 4, 2);
  c.C_s[0] = {2, 3, 2, 1, 1};
  c.C_s[1] = {3, 4, 2, 1, 1};
  c.C_s[2] = {4, 2, 2, 1, 1};
  expect_fault(c, "loop");
}

TEST(ConfigurationFaults, DetachedRowMustNotBeInAdjacency) {
  Configuration c = make_chain(3);
  c.C_s[1][4] = 0;  // row kept, magnets off: C_a(2,3) = 1 now disagrees
  expect_fault(c, "disagree");
}

TEST(ConfigurationFaults, DisconnectedModule) {
  Configuration c = make_chain(3);
  connect(c, 5, 6);
  c.C_s[2] = {5, 6, 2, 1, 1};
  expect_fault(c, "disconnected from module 1");
}

TEST(ConfigurationFaults, FaceUsedTwice) {
  Configuration c = make_chain(3);
  connect(c, 1, 3);
  c.C_s[2] = {1, 3, 2, 2, 1};  // module 1's back face is already in row 1
  expect_fault(c, "face 2 of module 1 is used twice");
}

TEST(ConfigurationFaults, ModuleOneFrontFace) {
  Configuration c = make_chain(2);
  c.C_s[0] = {2, 1, 2, 1, 1};  // module 2's back to module 1's front
  expect_fault(c, "module 1's front face");
}

TEST(ConfigurationFaults, OutOfRangeIndices) {
  Configuration c = make_chain(3);
  c.C_s[1] = {2, 11, 2, 1, 1};
  expect_fault(c, "module_j = 11 is out of range");
  Configuration d = make_chain(3);
  d.C_s[1] = {0, 3, 2, 1, 1};
  expect_fault(d, "module_i = 0 is out of range");
  Configuration e = make_chain(3);
  e.C_s[1] = {2, 3, 3, 1, 1};
  expect_fault(e, "face_i = 3 is out of range");
  Configuration f = make_chain(3);
  f.C_s[1] = {2, 3, 2, 1, 7};
  expect_fault(f, "connection = 7");
}

TEST(ConfigurationFaults, AdjacencyAndConnectionsDisagree) {
  Configuration c = make_chain(4);
  c.C_s[2] = {};  // C_a still connects 3 and 4
  expect_fault(c, "C_a and C_s disagree: C_a(3,4) = 1 but C_s has no connection");
  Configuration d = make_chain(3);
  d.C_a[1][2] = d.C_a[2][1] = 0;  // C_s still connects 2 and 3
  expect_fault(d, "C_s connects modules 2 and 3");
}

TEST(ConfigurationFaults, EmptyAndHeadless) {
  expect_fault(Configuration{}, "no connections");
  Configuration c;
  connect(c, 2, 3);
  c.C_s[0] = {2, 3, 2, 1, 1};
  expect_fault(c, "module 1");
}

TEST(ConfigurationFaults, GapInNumbering) {
  Configuration c;
  connect(c, 1, 2);
  connect(c, 2, 4);
  c.C_s[0] = {1, 2, 2, 1, 1};
  c.C_s[1] = {2, 4, 2, 1, 1};
  expect_fault(c, "module 3 is missing");
}

TEST(ConfigurationFaults, NotAChainLink) {
  Configuration c = make_chain(3);
  c.C_s[1] = {2, 3, 2, 2, 1};  // back face to back face
  expect_fault(c, "not a chain link");
}

TEST(ConfigurationFaults, ModuleCountThrowsOnInvalid) {
  Configuration c = make_chain(3);
  c.C_a[0][1] = 0;
  EXPECT_THROW(module_count(c), std::invalid_argument);
}

// Reconfiguration: a chain may shed tail modules, and nothing else.
TEST(SubConfiguration, ShorterChainsAreSubConfigurationsOfLongerOnes) {
  for (int n = kMinModules; n <= kMaxModules; ++n)
    for (int m = kMinModules; m <= kMaxModules; ++m) {
      const std::string fault = validate_sub_configuration(make_chain(n), make_chain(m));
      EXPECT_EQ(fault.empty(), m < n) << n << " -> " << m << ": " << fault;
    }
  EXPECT_NE(validate_sub_configuration(make_chain(4), make_chain(4)).find("sheds none"), std::string::npos);
  EXPECT_NE(validate_sub_configuration(make_chain(3), make_chain(5)).find("3 -> 5"), std::string::npos);
}

TEST(SubConfiguration, NamesAConnectionTheCurrentConfigurationLacks) {
  // Modules 1 and 2 docked the other way round (1's back face to 2's back face)
  // is not what the chain of 4 holds, even with fewer modules.
  Configuration flipped;
  connect(flipped, 1, 2);
  flipped.C_s[0] = {1, 2, kBackFace, kBackFace, 1};
  EXPECT_NE(validate_sub_configuration(make_chain(4), flipped).find("the new configuration is invalid"),
            std::string::npos);
  Configuration broken = make_chain(3);
  broken.C_a[0][1] = 0;
  EXPECT_NE(validate_sub_configuration(broken, make_chain(2)).find("the current configuration is invalid"),
            std::string::npos);
}

TEST(SubConfiguration, ModuleAtFaceFollowsTheChain) {
  const Configuration c = make_chain(3);
  EXPECT_EQ(module_at_face(c, 1, kFrontFace), 0);  // the head's front face stays free
  EXPECT_EQ(module_at_face(c, 1, kBackFace), 2);
  EXPECT_EQ(module_at_face(c, 2, kFrontFace), 1);
  EXPECT_EQ(module_at_face(c, 2, kBackFace), 3);
  EXPECT_EQ(module_at_face(c, 3, kBackFace), 0);
  EXPECT_EQ(c, make_chain(3));
  EXPECT_NE(c, make_chain(4));
}

TEST(ConfigurationYaml, RoundTripThroughFile) {
  const std::string path = ::testing::TempDir() + "/config_roundtrip.yaml";
  for (int n = kMinModules; n <= kMaxModules; ++n) {
    save_configuration(path, make_chain(n));
    const Configuration loaded = load_configuration(path);
    EXPECT_EQ(loaded.C_a, make_chain(n).C_a);
    EXPECT_EQ(loaded.C_s, make_chain(n).C_s);
  }
  std::remove(path.c_str());
}

TEST(ConfigurationYaml, ShorthandModules) {
  EXPECT_EQ(configuration_from_yaml("modules: 5").C_s, make_chain(5).C_s);
}

namespace {
void expect_yaml_error(const std::string& text, const std::string& needle) {
  try {
    configuration_from_yaml(text, "robot.yaml");
    FAIL() << "expected an error containing '" << needle << "'";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("robot.yaml"), std::string::npos) << message;
    EXPECT_NE(message.find(needle), std::string::npos) << message;
  }
}
}  // namespace

TEST(ConfigurationYaml, BadFilesNameFileAndField) {
  expect_yaml_error("modules: 12", "'modules'");
  expect_yaml_error("modules: two", "'modules'");
  expect_yaml_error("C_a: [[0, 1]]\nC_s: []", "'C_a'");
  expect_yaml_error("C_s: []", "'C_a': missing");
  expect_yaml_error("wheels: 4", "'wheels': unknown field");
  expect_yaml_error("C_a: [", "not valid YAML");
  expect_yaml_error("- 1\n- 2", "expected a mapping");
  std::string c_a = "C_a:\n";
  for (int i = 0; i < kMaxModules; ++i) c_a += "  - [0,0,0,0,0,0,0,0,0,0]\n";
  expect_yaml_error(c_a + "C_s:\n  - [1, 2, 2, 1]\n", "'C_s[0]'");
  expect_yaml_error(c_a + "C_s:\n  - [1, 2, 2, 1, x]\n", "'C_s[0][4]'");
  expect_yaml_error(c_a + "C_s:\n  - [1, 2, 2, 1, 1]\n", "C_a and C_s disagree");
}

TEST(ConfigurationYaml, MissingFileNamesPath) {
  try {
    load_configuration("/nonexistent/robot.yaml");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.yaml"), std::string::npos);
  }
}
