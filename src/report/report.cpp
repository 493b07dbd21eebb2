#include "report/report.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "common/file_io.hpp"
#include "report/plots.hpp"
#include "report/process.hpp"

namespace fs = std::filesystem;

namespace comorph::report {
namespace {

// A number with `decimals` digits after the point, or "n/a" when absent.
std::string num(double x, int decimals) { return std::isfinite(x) ? fmt::format("{:.{}f}", x, decimals) : "n/a"; }

// The paper's numbers as the paper prints them (shortest exact text: 2.28, 3090).
std::string paper_num(double x) { return std::isfinite(x) ? fmt::format("{}", x) : "n/a"; }

std::string percent(double fraction) { return std::isfinite(fraction) ? num(100.0 * fraction, 1) : "n/a"; }

double lookup(const std::map<std::string, double>& m, const std::string& key) {
  auto it = m.find(key);
  return it == m.end() ? std::nan("") : it->second;
}

bool matches(const RunDir& run, const RunMatch& match) {
  return run.info.kind == match.kind && run.info.algo == match.algo &&
         (match.modules == 0 || run.info.modules == match.modules) && run.info.scenario == match.train_scenario &&
         run.evals.count(match.eval_scenario);
}

// One figure over a column's runs: "mean [min, max]" over the runs that have
// it, "value (1 seed)" for a single run; runs without it (no successful
// episode has no time) are counted as "(k of n seeds)".
std::string over_seeds(const std::vector<double>& values, int decimals) {
  std::vector<double> finite;
  for (double v : values)
    if (std::isfinite(v)) finite.push_back(v);
  if (finite.empty()) return "n/a";
  const auto [lo, hi] = std::minmax_element(finite.begin(), finite.end());
  double mean = 0;
  for (double v : finite) mean += v / static_cast<double>(finite.size());
  std::string s = finite.size() == 1 ? fmt::format("{} (1 seed)", num(mean, decimals))
                                     : fmt::format("{} [{}, {}]", num(mean, decimals), num(*lo, decimals), num(*hi, decimals));
  if (finite.size() < values.size() && values.size() > 1)
    s += fmt::format(" ({} of {} seeds)", finite.size(), values.size());
  return s;
}

// The most frequent configuration sequence and its share of the episodes.
std::string dominant(const std::map<std::string, int>& counts) {
  int total = 0, best = -1;
  std::string best_seq;
  for (const auto& [seq, n] : counts) {
    total += n;
    if (n > best) best = n, best_seq = seq;
  }
  if (total == 0) return "n/a";
  return fmt::format("{} ({:.0f} %)", best_seq.empty() ? "none" : best_seq, 100.0 * best / total);
}

std::string all_counts(const std::map<std::string, int>& counts) {
  std::vector<std::string> parts;
  for (const auto& [seq, n] : counts) parts.push_back(fmt::format("{}: {}", seq.empty() ? "none" : seq, n));
  return parts.empty() ? "n/a" : fmt::format("{}", fmt::join(parts, ", "));
}

std::string md_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|') out += "\\|";
    else if (c == '\n') out += ' ';
    else out += c;
  }
  return out;
}

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

ReportBlock heading(int level, std::string text) {
  ReportBlock b;
  b.kind = ReportBlock::Kind::Heading;
  b.level = level;
  b.text = std::move(text);
  return b;
}

ReportBlock paragraph(std::string text) {
  ReportBlock b;
  b.kind = ReportBlock::Kind::Paragraph;
  b.text = std::move(text);
  return b;
}

ReportBlock image(std::string path, std::string caption) {
  ReportBlock b;
  b.kind = ReportBlock::Kind::Image;
  b.image = std::move(path);
  b.text = std::move(caption);
  return b;
}

ReportBlock table(std::vector<std::string> header, std::vector<std::vector<std::string>> rows) {
  ReportBlock b;
  b.kind = ReportBlock::Kind::Table;
  b.header = std::move(header);
  b.rows = std::move(rows);
  return b;
}

std::string describe(const RunInfo& info) {
  std::string s = info.kind == "fixed" ? fmt::format("fixed {} modules", info.modules)
                                       : fmt::format("hierarchical (up to {} modules)", info.modules);
  s += fmt::format(", {}, trained on '{}'", info.algo, info.scenario);
  if (info.episodes > 0) s += fmt::format(", {} episodes", info.episodes);
  if (!info.preset.empty()) s += fmt::format(", preset {}", info.preset);
  return s;
}

}  // namespace

std::vector<const RunDir*> column_runs(const PaperColumn& column, const std::vector<RunDir>& runs) {
  std::vector<const RunDir*> found;
  for (const auto& r : runs)
    if (matches(r, column.match) && (found.empty() || r.config_key == found.front()->config_key)) found.push_back(&r);
  return found;
}

std::string comparison_table_legend() {
  return "Every cell reads \"ours / paper\". Ours is the mean over the training seeds of the column's run "
         "configuration with [lowest, highest] over the seeds, or the value of a single seed, marked \"(1 seed)\"; "
         "a dash marks a column with no run.";
}

ReportBlock comparison_table(const PaperTable& paper, const std::vector<RunDir>& runs) {
  std::vector<std::string> header = {""};
  std::vector<std::vector<const EvalSummary*>> ours;  // per column: its runs' evaluations
  std::vector<std::vector<const RunDir*>> seeds;
  for (const auto& col : paper.columns) {
    const auto found = column_runs(col, runs);
    if (found.empty()) header.push_back(col.label);
    else if (found.size() == 1) header.push_back(fmt::format("{} [{}]", col.label, found.front()->info.name));
    else header.push_back(fmt::format("{} [{} runs]", col.label, found.size()));
    std::vector<const EvalSummary*> evals;
    for (const RunDir* r : found) evals.push_back(&r->evals.at(col.match.eval_scenario));
    ours.push_back(evals);
    seeds.push_back(found);
  }
  std::vector<std::vector<std::string>> rows;
  auto text_row = [&](const std::string& name, auto our_text, auto paper_text) {
    std::vector<std::string> r = {name};
    for (size_t c = 0; c < paper.columns.size(); ++c)
      r.push_back(fmt::format("{} / {}", c < ours.size() && !ours[c].empty() ? our_text(c) : "—",
                              paper_text(paper.columns[c])));
    rows.push_back(std::move(r));
  };
  // A figure of our evaluations (value_of) over the seeds, beside the paper's (paper_value).
  auto row = [&](const std::string& name, auto value_of, int decimals, auto paper_value) {
    text_row(
        name,
        [&](size_t c) {
          std::vector<double> values;
          for (const EvalSummary* m : ours[c]) values.push_back(value_of(*m));
          return over_seeds(values, decimals);
        },
        [&](const PaperColumn& p) { return paper_num(paper_value(p)); });
  };
  row("Time (s)", [](const EvalSummary& m) { return m.time_s; }, 1, [](const PaperColumn& p) { return p.time_s; });
  row("Battery (J)", [](const EvalSummary& m) { return m.energy_J; }, 0,
      [](const PaperColumn& p) { return p.energy_J; });
  // The paper's stair heights (the table compares ours at the same heights), then the average.
  std::vector<std::pair<double, std::string>> heights;
  for (const auto& column : paper.columns)
    for (const auto& [key, percent] : column.success_percent)
      if (key != "avg" && std::find_if(heights.begin(), heights.end(), [&](const auto& h) { return h.second == key; }) ==
                              heights.end())
        heights.emplace_back(std::stod(key), key);
  std::sort(heights.begin(), heights.end());
  std::vector<std::string> keys;
  for (const auto& [height, key] : heights) keys.push_back(key);
  keys.push_back("avg");
  for (const std::string& key : keys) {
    const std::string name = key == "avg" ? "Success avg (%)" : fmt::format("Success {} m (%)", key);
    row(name, [key](const EvalSummary& m) { return 100.0 * lookup(m.success_rate, key); }, 1,
        [key](const PaperColumn& p) { return lookup(p.success_percent, key); });
  }
  row("F(H)", [](const EvalSummary& m) { return m.F; }, 3, [](const PaperColumn& p) { return p.F; });
  auto not_given = [](const PaperColumn&) { return std::string("n/a"); };
  text_row(
      "Episodes",
      [&](size_t c) {
        std::vector<std::string> counts;
        for (const EvalSummary* m : ours[c]) counts.push_back(std::to_string(m->episodes));
        const bool same = std::all_of(counts.begin(), counts.end(), [&](const auto& n) { return n == counts.front(); });
        return same ? counts.front() + (counts.size() > 1 ? " each" : "") : fmt::format("{}", fmt::join(counts, ", "));
      },
      not_given);
  text_row(
      "Training seeds",
      [&](size_t c) {
        std::vector<std::string> list;
        for (const RunDir* r : seeds[c]) list.push_back(r->config_key.empty() ? "?" : std::to_string(r->seed));
        return fmt::format("{}", fmt::join(list, ", "));
      },
      not_given);
  return table(std::move(header), std::move(rows));
}

std::string render_markdown(const std::vector<ReportBlock>& blocks) {
  std::string out;
  for (const auto& b : blocks) {
    switch (b.kind) {
      case ReportBlock::Kind::Heading: out += std::string(b.level, '#') + " " + b.text + "\n\n"; break;
      case ReportBlock::Kind::Paragraph: out += b.text + "\n\n"; break;
      case ReportBlock::Kind::Image: out += fmt::format("![{}]({})\n\n", b.text, b.image); break;
      case ReportBlock::Kind::Table: {
        std::vector<std::string> h, sep;
        for (const auto& c : b.header) h.push_back(md_escape(c)), sep.push_back("---");
        out += fmt::format("| {} |\n|{}|\n", fmt::join(h, " | "), fmt::join(sep, "|"));
        for (const auto& r : b.rows) {
          std::vector<std::string> cells;
          for (const auto& c : r) cells.push_back(md_escape(c));
          out += fmt::format("| {} |\n", fmt::join(cells, " | "));
        }
        out += "\n";
        break;
      }
    }
  }
  return out;
}

std::string render_html(const std::vector<ReportBlock>& blocks, const std::string& title) {
  std::string out = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n"
      "<style>body{{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em}}"
      "table{{border-collapse:collapse;margin:1em 0}}th,td{{border:1px solid #bbb;padding:4px 8px;"
      "text-align:right}}th:first-child,td:first-child{{text-align:left}}img{{max-width:100%}}</style>\n"
      "</head>\n<body>\n",
      html_escape(title));
  for (const auto& b : blocks) {
    switch (b.kind) {
      case ReportBlock::Kind::Heading: out += fmt::format("<h{0}>{1}</h{0}>\n", b.level, html_escape(b.text)); break;
      case ReportBlock::Kind::Paragraph: out += fmt::format("<p>{}</p>\n", html_escape(b.text)); break;
      case ReportBlock::Kind::Image:
        out += fmt::format("<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
                           html_escape(b.image), html_escape(b.text), html_escape(b.text));
        break;
      case ReportBlock::Kind::Table:
        out += "<table>\n<tr>";
        for (const auto& c : b.header) out += fmt::format("<th>{}</th>", html_escape(c));
        out += "</tr>\n";
        for (const auto& r : b.rows) {
          out += "<tr>";
          for (const auto& c : r) out += fmt::format("<td>{}</td>", html_escape(c));
          out += "</tr>\n";
        }
        out += "</table>\n";
        break;
    }
  }
  return out + "</body>\n</html>\n";
}

namespace {

ReportResult write_report_files(const std::vector<RunDir>& runs, const std::vector<CurveSeries>& series,
                                const PaperReference& paper, const std::string& ref_path,
                                const ReportOptions& options) {
  const fs::path out(options.out_dir);
  ReportResult result;

  std::vector<ReportBlock> doc;
  doc.push_back(heading(1, "comorph report"));
  doc.push_back(paragraph(fmt::format(
      "Runs: {}. {} The paper: {}; numbers from {}. "
      "Time and Battery average the successful evaluation episodes only; success is counted per stair "
      "height and averaged over the heights.",
      runs.size(), comparison_table_legend(), paper.source, ref_path)));
  if (!paper.protocol.empty()) doc.push_back(paragraph("Paper protocol: " + paper.protocol));

  for (const auto& t : paper.tables) {
    doc.push_back(heading(2, t.title));
    doc.push_back(comparison_table(t, runs));
  }
  if (!options.missing.empty())
    doc.push_back(paragraph(fmt::format("Missing, so not in the tables: {}.", fmt::join(options.missing, "; "))));
  for (const auto& note : paper.notes) doc.push_back(paragraph("Paper: " + note));

  // Training curves, all runs in one figure as in Fig. 9.
  doc.push_back(heading(2, "Training curves"));
  const bool have_gnuplot = !find_executable("gnuplot").empty();
  if (have_gnuplot || options.require_plots) {
    CurveOptions curve;
    curve.window = options.curve_window;
    curve.title = "Training curves (score = return of R1)";
    const std::string png = (out / "training-curves.png").string();
    plot_training_curves(series, png, curve);  // throws naming gnuplot when it is missing
    result.images.push_back(png);
    doc.push_back(image("training-curves.png",
                        fmt::format("Score per episode with its moving average over {} episodes, and the success "
                                    "rate over the last {} episodes, one curve per run",
                                    options.curve_window, options.curve_window)));
  } else {
    doc.push_back(paragraph("Training curves not drawn: gnuplot is not installed (Debian package gnuplot-nox)."));
  }

  // Each run: what it is, every evaluation, configurations chosen per height.
  doc.push_back(heading(2, "Runs"));
  for (const auto& r : runs) {
    doc.push_back(heading(3, r.info.name));
    doc.push_back(paragraph(fmt::format("{}: {}.{}", r.path, describe(r.info),
                                        r.info.notes.empty() ? "" : " " + r.info.notes)));
    // A success column per stair height any of the run's evaluations had.
    std::vector<std::pair<double, std::string>> heights;
    for (const auto& [scenario, m] : r.evals)
      for (const std::string& key : stair_keys(m)) heights.emplace_back(std::stod(key), key);
    std::sort(heights.begin(), heights.end());
    heights.erase(std::unique(heights.begin(), heights.end()), heights.end());
    std::vector<std::string> header{"Evaluation", "Episodes"};
    for (const auto& [height, key] : heights) header.push_back(fmt::format("Success {} m (%)", key));
    for (const char* name : {"Success avg (%)", "Time (s)", "Battery (J)", "F(H)", "Terminations (episodes)"})
      header.push_back(name);
    std::vector<std::vector<std::string>> rows;
    for (const auto& [scenario, m] : r.evals) {
      std::vector<std::string> terms;
      for (const auto& [why, n] : m.terminations) terms.push_back(fmt::format("{}: {}", why, n));
      std::vector<std::string> row{scenario, std::to_string(m.episodes)};
      for (const auto& [height, key] : heights) row.push_back(percent(lookup(m.success_rate, key)));
      for (const std::string& cell : {percent(lookup(m.success_rate, "avg")), num(m.time_s, 1), num(m.energy_J, 0),
                                      num(m.F, 3), fmt::format("{}", fmt::join(terms, ", "))})
        row.push_back(cell);
      rows.push_back(std::move(row));
    }
    doc.push_back(table(std::move(header), std::move(rows)));

    // Chosen configurations per stair height, with the paper's where it gives them.
    std::map<std::string, std::string> paper_choice;
    for (const auto& t : paper.tables)
      for (const auto& c : t.columns)
        if (c.match.kind == r.info.kind && c.match.algo == r.info.algo && !c.configurations.empty())
          paper_choice = c.configurations;
    std::vector<std::vector<std::string>> conf_rows;
    for (const auto& [scenario, m] : r.evals)
      for (const auto& [height, counts] : m.configurations) {
        auto it = paper_choice.find(height);
        conf_rows.push_back({scenario, height, dominant(counts), all_counts(counts),
                             it == paper_choice.end() ? "n/a" : it->second});
      }
    doc.push_back(paragraph("Configurations chosen (modules of each configuration, in order; \"4->2\" = 4 modules "
                            "on the stairs, then 2 after them):"));
    doc.push_back(table({"Evaluation", "Stair height (m)", "Most chosen (share of episodes)",
                         "All choices (episodes)", "Paper"},
                        std::move(conf_rows)));

    // Keyframe strips that `comorph render` left in the run directory.
    for (const auto& entry : fs::directory_iterator(r.path)) {
      const std::string name = entry.path().filename().string();
      if (entry.is_regular_file() && name.rfind("render", 0) == 0 && entry.path().extension() == ".png") {
        const std::string copied = fmt::format("{}-{}", r.info.name, name);
        fs::copy_file(entry.path(), out / copied, fs::copy_options::overwrite_existing);
        result.images.push_back((out / copied).string());
        doc.push_back(image(copied, fmt::format("{}: keyframes of {}", r.info.name, name)));
      }
    }
  }

  result.markdown_path = (out / "report.md").string();
  result.html_path = (out / "report.html").string();
  write_file_atomic(result.markdown_path, render_markdown(doc));
  write_file_atomic(result.html_path, render_html(doc, "comorph report"));
  spdlog::info("report: {} and {} ({} images)", result.markdown_path, result.html_path, result.images.size());
  return result;
}

}  // namespace

ReportResult write_report(const std::vector<std::string>& run_dirs, const ReportOptions& options) {
  if (run_dirs.empty()) throw std::invalid_argument("report: no run directories given");
  if (options.out_dir.empty()) throw std::invalid_argument("report: no output directory given");
  const std::string ref_path = options.reference_path.empty() ? default_paper_reference_path() : options.reference_path;
  const PaperReference paper = load_paper_reference(ref_path);
  // Everything is read before anything is written: a damaged input leaves no output behind.
  std::vector<RunDir> runs;
  for (const auto& d : run_dirs) runs.push_back(load_run_dir(d, options.config_identity));
  std::vector<CurveSeries> series;
  for (const auto& r : runs) series.push_back({r.info.name, read_episodes_csv(r.episodes_csv)});
  const bool created = !fs::exists(options.out_dir);
  fs::create_directories(options.out_dir);
  try {
    return write_report_files(runs, series, paper, ref_path, options);
  } catch (...) {
    std::error_code ignored;
    if (created) fs::remove_all(options.out_dir, ignored);
    throw;
  }
}

}  // namespace comorph::report
