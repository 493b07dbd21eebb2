// `comorph report`: the paper's tables with our numbers beside the paper's,
// training curves and the configurations chosen, as Markdown and HTML.
#pragma once

#include <string>
#include <vector>

#include "report/paper_reference.hpp"
#include "report/run_dir.hpp"

namespace comorph::report {

struct ReportOptions {
  std::string out_dir;              // created if needed; gets report.md, report.html, images
  std::string reference_path;       // paper tables YAML; "" = default_paper_reference_path()
  int curve_window = 100;           // episodes in the moving averages of the training curves
  bool require_plots = true;        // false: without gnuplot, write the report without curves (and say so)
  std::vector<std::string> missing; // runs an experiment lacks, one line each, listed under the tables
  ConfigIdentity config_identity;   // how runs' config.yaml are compared (load_run_dir)
};

struct ReportResult {
  std::string markdown_path;
  std::string html_path;
  std::vector<std::string> images;  // PNG files written or copied into out_dir
};

// A report document: blocks rendered the same way to Markdown and to HTML.
struct ReportBlock {
  enum class Kind { Heading, Paragraph, Table, Image } kind = Kind::Paragraph;
  int level = 2;                                  // heading level
  std::string text;                               // heading, paragraph, image caption
  std::vector<std::string> header;                // table
  std::vector<std::vector<std::string>> rows;     // table
  std::string image;                              // image path, relative to the report
};

std::string render_markdown(const std::vector<ReportBlock>& blocks);
std::string render_html(const std::vector<ReportBlock>& blocks, const std::string& title);

// The runs a paper column shows: those of `runs` that match it (RunMatch)
// and have the configuration of the first match (RunDir::config_key), i.e.
// that configuration's training seeds. Empty when none matches.
std::vector<const RunDir*> column_runs(const PaperColumn& column, const std::vector<RunDir>& runs);

// The paper table with "ours / paper" in every cell. Ours is the mean over
// the column's runs (column_runs) with [min, max] over them, or the one run's
// value marked "(1 seed)"; a row names the training seeds.
ReportBlock comparison_table(const PaperTable& table, const std::vector<RunDir>& runs);

// What every comparison table's cell means, as a paragraph.
std::string comparison_table_legend();

// Loads every run directory (throws naming what is missing), writes the report.
ReportResult write_report(const std::vector<std::string>& run_dirs, const ReportOptions& options);

}  // namespace comorph::report
