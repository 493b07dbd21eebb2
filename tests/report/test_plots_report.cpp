// Training curves and the report, from tiny run directories written here.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "report/plots.hpp"
#include "report/process.hpp"
#include "report/report.hpp"
#include "report/video.hpp"

namespace fs = std::filesystem;

namespace comorph::report {
namespace {

bool have_gnuplot() { return !find_executable("gnuplot").empty(); }

// A PNG file: exists, non-empty, starts with the PNG signature.
void expect_png(const fs::path& path) {
  ASSERT_TRUE(fs::is_regular_file(path)) << path;
  EXPECT_GT(fs::file_size(path), 1000u) << path;
  std::ifstream in(path, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG") << path;
}

void expect_png_header(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG") << path;
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Episodes whose success probability grows with training, like a learning run.
std::vector<EpisodeRecord> fake_episodes(int n, int modules, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double heights[] = {0.04, 0.06, 0.08};
  std::vector<EpisodeRecord> out;
  for (int i = 0; i < n; ++i) {
    EpisodeRecord r;
    r.episode = i;
    r.seed = seed * 1000 + i;
    r.scenario = "default";
    r.stair_height_m = heights[rng() % 3];
    r.obstacles = 6;
    r.success = u(rng) < 0.1 + 0.8 * i / n;
    r.termination = r.success ? "success" : (u(rng) < 0.5 ? "collision" : "timeout");
    r.time_s = r.success ? 35 + 20 * u(rng) : 112;
    r.energy_J = 27.0 * modules * r.time_s;
    r.distance_fraction = r.success ? 1.0 : u(rng);
    r.return_R1 = 200 * r.distance_fraction + (r.success ? 100 : -10) + 20 * u(rng);
    r.configurations = modules == 10 ? std::vector<int>{2 + 2 * static_cast<int>(rng() % 3), 2}
                                     : std::vector<int>{modules};
    r.modules_total = r.configurations.front();
    out.push_back(r);
  }
  return out;
}

struct TinyRuns {
  fs::path root;
  fs::path hier, fixed4;
  EvalSummary hier_eval, fixed4_eval, hier_eval7;

  TinyRuns() {
    root = fs::temp_directory_path() / fmt::format("comorph-report-test-{}", ::getpid());
    fs::remove_all(root);
    hier = root / "hier-td3";
    fixed4 = root / "fixed4";
    fs::create_directories(hier);
    fs::create_directories(fixed4);
    std::ofstream(hier / "run.yaml") << "kind: hierarchical\nmodules: 10\nalgo: td3\nscenario: default\n";
    std::ofstream(fixed4 / "run.yaml") << "name: fixed-4\nkind: fixed\nmodules: 4\nalgo: td3\n";
    write_episodes_csv((hier / "episodes.csv").string(), fake_episodes(300, 10, 1));
    write_episodes_csv((fixed4 / "episodes.csv").string(), fake_episodes(250, 4, 2));
    hier_eval = summarize(fake_episodes(60, 10, 3));
    hier_eval7 = summarize(fake_episodes(30, 10, 4));
    fixed4_eval = summarize(fake_episodes(60, 4, 5));
    write_metrics_json((hier / "eval-default.json").string(), hier_eval);
    write_metrics_json((hier / "eval-obstacles7.json").string(), hier_eval7);
    write_metrics_json((hier / "eval-mixed.json").string(), hier_eval7);  // trained on default: not the mixed column
    write_metrics_json((fixed4 / "eval-default.json").string(), fixed4_eval);
  }
  ~TinyRuns() { fs::remove_all(root); }
};

TEST(Plots, MovingAverageIsTrailing) {
  const auto avg = moving_average({2, 4, 6, 8}, 2);
  ASSERT_EQ(avg.size(), 4u);
  EXPECT_DOUBLE_EQ(avg[0], 2);  // only one value so far
  EXPECT_DOUBLE_EQ(avg[1], 3);
  EXPECT_DOUBLE_EQ(avg[2], 5);
  EXPECT_DOUBLE_EQ(avg[3], 7);
  EXPECT_THROW(moving_average({1}, 0), std::invalid_argument);
}

TEST(Plots, TrainingCurvesPng) {
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot is not installed";
  TinyRuns runs;
  const fs::path png = runs.root / "curves.png";
  plot_training_curves({{"a", fake_episodes(200, 4, 7)}, {"b's run", fake_episodes(150, 6, 8)}}, png.string());
  expect_png(png);
  EXPECT_TRUE(fs::is_regular_file(runs.root / "curves.gp"));
  EXPECT_TRUE(fs::is_regular_file(runs.root / "curves-1.dat"));
  EXPECT_THROW(plot_training_curves({{"empty", {}}}, (runs.root / "e.png").string()), std::invalid_argument);
}

// With gnuplot off PATH, plotting (and so the report) stops with a message
// naming the tool and its Debian package.
TEST(Plots, MissingGnuplotIsNamed) {
  TinyRuns runs;
  const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", (runs.root / "empty-bin").c_str(), 1);
  std::string msg;
  try {
    plot_training_curves({{"a", fake_episodes(20, 4, 7)}}, (runs.root / "c.png").string());
  } catch (const std::runtime_error& e) {
    msg = e.what();
  }
  ReportOptions options;
  options.out_dir = (runs.root / "out").string();
  EXPECT_THROW(write_report({runs.hier.string()}, options), std::runtime_error);
  setenv("PATH", saved.c_str(), 1);
  EXPECT_NE(msg.find("'gnuplot' is not installed"), std::string::npos) << msg;
  EXPECT_NE(msg.find("gnuplot-nox"), std::string::npos) << msg;
}

TEST(Report, TablesHoldThePapersNumbersAndOurs) {
  TinyRuns runs;
  ReportOptions options;
  options.out_dir = (runs.root / "out").string();
  options.curve_window = 20;
  options.require_plots = have_gnuplot();
  const ReportResult result = write_report({runs.hier.string(), runs.fixed4.string()}, options);
  const std::string md = slurp(result.markdown_path);
  const std::string html = slurp(result.html_path);

  // Table I, hierarchical column: ours beside the paper's 43.1 s, 3090 J, 89.3 %, F 1.136.
  EXPECT_NE(md.find(fmt::format("| {:.1f} (1 seed) / 43.1 |", runs.hier_eval.time_s)), std::string::npos) << md;
  EXPECT_NE(md.find(fmt::format("| {:.0f} (1 seed) / 3090 |", runs.hier_eval.energy_J)), std::string::npos) << md;
  EXPECT_NE(md.find(fmt::format("| {:.1f} (1 seed) / 89.3 |", 100 * runs.hier_eval.success_rate.at("avg"))),
            std::string::npos) << md;
  EXPECT_NE(md.find(fmt::format("| {:.3f} (1 seed) / 1.136 |", runs.hier_eval.F)), std::string::npos) << md;
  // Fixed 4: ours beside 42.7 s and 78.5 % at 0.04 m; fixed 2 has no run.
  EXPECT_NE(md.find(fmt::format("| {:.1f} (1 seed) / 42.7 |", runs.fixed4_eval.time_s)), std::string::npos) << md;
  EXPECT_NE(md.find(fmt::format("| {:.1f} (1 seed) / 78.5 |", 100 * runs.fixed4_eval.success_rate.at("0.04"))),
            std::string::npos) << md;
  EXPECT_NE(md.find("| — / 56.2 |"), std::string::npos) << md;
  // Table II: 7 obstacles from eval-obstacles7.json; SAC has no run.
  EXPECT_NE(md.find(fmt::format("| {:.1f} (1 seed) / 50.2 |", runs.hier_eval7.time_s)), std::string::npos) << md;
  EXPECT_NE(md.find("| — / 57.6 |"), std::string::npos) << md;
  // The mixed column wants a run trained on the mixed scene (match.train): the default-trained one is not it.
  EXPECT_NE(md.find("| — / 25 |"), std::string::npos) << md;
  EXPECT_NE(md.find("Table I:"), std::string::npos);
  EXPECT_NE(md.find("Table II:"), std::string::npos);
  // Configurations per stair height, with the paper's choice beside.
  EXPECT_NE(md.find("| default | 0.06 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 4->2 |"), std::string::npos) << md;
  EXPECT_NE(html.find("<table>"), std::string::npos);
  EXPECT_NE(html.find(fmt::format("<td>{:.1f} (1 seed) / 43.1</td>", runs.hier_eval.time_s)), std::string::npos);

  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot is not installed: no training curves to check";
  ASSERT_EQ(result.images.size(), 1u);
  expect_png(result.images[0]);
  EXPECT_NE(md.find("![Score per episode"), std::string::npos);
  EXPECT_NE(html.find("<img src=\"training-curves.png\""), std::string::npos);
}

// Runs of one configuration trained with different seeds (config.yaml but
// trainer.seed the same) are one column: each figure their mean with
// [min, max]; a run of another configuration matching the same column is not
// averaged in.
TEST(Report, ColumnAveragesTheSeedsOfOneConfiguration) {
  TinyRuns runs;
  auto config = [](int seed, int episodes) {
    return fmt::format("trainer:\n  mode: fixed\n  seed: {}\n  episodes: {}\n", seed, episodes);
  };
  std::ofstream(runs.fixed4 / "config.yaml") << config(1, 250);
  const fs::path seed2 = runs.root / "fixed-4-seed-2", other = runs.root / "fixed-4-other";
  for (const auto& [dir, text] : {std::pair{seed2, config(2, 250)}, std::pair{other, config(3, 999)}}) {
    fs::create_directories(dir);
    fs::copy_file(runs.fixed4 / "run.yaml", dir / "run.yaml");
    fs::copy_file(runs.fixed4 / "episodes.csv", dir / "episodes.csv");
    std::ofstream(dir / "config.yaml") << text;
  }
  const EvalSummary second = summarize(fake_episodes(60, 4, 6));
  write_metrics_json((seed2 / "eval-default.json").string(), second);
  write_metrics_json((other / "eval-default.json").string(), summarize(fake_episodes(60, 4, 7)));
  std::vector<RunDir> loaded;
  for (const auto& d : {runs.fixed4, other, seed2}) loaded.push_back(load_run_dir(d.string()));
  EXPECT_EQ(loaded[2].seed, 2);

  const PaperReference paper = load_paper_reference(default_paper_reference_path());
  const std::string md = render_markdown({comparison_table(paper.tables.at(0), loaded)});
  const double a = 100 * runs.fixed4_eval.success_rate.at("avg"), b = 100 * second.success_rate.at("avg");
  ASSERT_NE(a, b);
  EXPECT_NE(md.find(fmt::format("| {:.1f} [{:.1f}, {:.1f}] / 70.6 |", (a + b) / 2, std::min(a, b), std::max(a, b))),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("Fixed 4 [2 runs]"), std::string::npos) << md;
  EXPECT_NE(md.find("| 60 each / n/a |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 1, 2 / n/a |"), std::string::npos) << md;  // the seeds; not the other configuration's 3
}

// A keyframe strip left by `comorph render` in a run directory is copied and shown.
TEST(Report, IncludesKeyframeStripsOfARun) {
  TinyRuns runs;
  Image strip;
  strip.width = 40;
  strip.height = 10;
  strip.rgb.assign(40 * 10 * 3, 200);
  write_png(strip, (runs.hier / "render-7.png").string());
  expect_png_header(runs.hier / "render-7.png");
  ReportOptions options;
  options.out_dir = (runs.root / "out").string();
  options.require_plots = false;
  const ReportResult result = write_report({runs.hier.string()}, options);
  const fs::path copied = runs.root / "out" / "hier-td3-render-7.png";
  EXPECT_TRUE(fs::is_regular_file(copied));
  EXPECT_NE(std::find(result.images.begin(), result.images.end(), copied.string()), result.images.end());
  EXPECT_NE(slurp(result.markdown_path).find("](hier-td3-render-7.png)"), std::string::npos);
}

TEST(Report, MissingFilesAreNamed) {
  TinyRuns runs;
  fs::remove(runs.fixed4 / "episodes.csv");
  fs::remove(runs.fixed4 / "eval-default.json");
  ReportOptions options;
  options.out_dir = (runs.root / "out").string();
  try {
    write_report({runs.hier.string(), runs.fixed4.string()}, options);
    FAIL() << "wrote a report from an incomplete run directory";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find((runs.fixed4 / "episodes.csv").string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("eval-<scenario>.json"), std::string::npos) << msg;
  }
  fs::remove(runs.hier / "run.yaml");
  EXPECT_THROW(write_report({runs.hier.string()}, options), std::runtime_error);
}

// A damaged episodes.csv is refused with the file, the line and the fault,
// and no output directory is left behind.
TEST(Report, ADamagedEpisodeLogIsRefusedAndLeavesNoOutput) {
  TinyRuns runs;
  const fs::path csv = runs.fixed4 / "episodes.csv";
  const std::string good = slurp(csv.string());
  const std::string header = good.substr(0, good.find('\n') + 1);
  const std::string row1 = good.substr(header.size(), good.find('\n', header.size()) + 1 - header.size());
  struct Damage {
    std::string text, expected;
  };
  std::string with_nan;
  {
    // return_R1 is the 11th column: replace it by nan.
    std::vector<std::string> fields;
    std::string row = row1.substr(0, row1.size() - 1);
    for (std::size_t start = 0, comma = 0; comma != std::string::npos; start = comma + 1) {
      comma = row.find(',', start);
      fields.push_back(row.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    }
    fields[10] = "nan";
    with_nan = header + fmt::format("{}\n", fmt::join(fields, ","));
  }
  const std::vector<Damage> damages{
      {header + "garbage\n", ":2:"},
      {header + row1.substr(0, row1.size() / 2), ":2:"},  // a row cut mid-field
      {"episode_no" + good.substr(good.find(',')), "header lacks column 'episode'"},
      {"", ":1:1: empty file"},
      {with_nan, "'nan' is not a finite number"},
      {header + row1 + row1, "episode 0 appears twice (also on line 2)"}};
  ReportOptions options;
  options.out_dir = (runs.root / "out").string();
  for (const Damage& d : damages) {
    std::ofstream(csv, std::ios::trunc) << d.text;
    try {
      write_report({runs.hier.string(), runs.fixed4.string()}, options);
      ADD_FAILURE() << "accepted " << d.text.substr(0, 200);
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(csv.string()), std::string::npos) << msg;
      EXPECT_NE(msg.find(d.expected), std::string::npos) << msg;
    }
    EXPECT_FALSE(fs::exists(options.out_dir)) << d.expected;
  }
}

TEST(Report, BadRunYamlIsNamed) {
  TinyRuns runs;
  std::ofstream(runs.fixed4 / "run.yaml") << "kind: fixed\nmodules: 4\nalgo: ppo\n";
  try {
    load_run_dir(runs.fixed4.string());
    FAIL() << "accepted algo ppo";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("run.yaml: algo 'ppo'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace comorph::report
