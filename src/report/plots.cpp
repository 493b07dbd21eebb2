#include "report/plots.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "common/file_io.hpp"
#include "report/process.hpp"

namespace comorph::report {
namespace {

// gnuplot single-quoted string: a quote is written twice.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string stem(const std::string& png_path) {
  const std::string ext = ".png";
  if (png_path.size() > ext.size() && png_path.compare(png_path.size() - ext.size(), ext.size(), ext) == 0)
    return png_path.substr(0, png_path.size() - ext.size());
  return png_path;
}

// Colour-blind-safe palette (Okabe-Ito), cycled over runs.
const char* colour(size_t i) {
  static const char* palette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"};
  return palette[i % (sizeof(palette) / sizeof(palette[0]))];
}

}  // namespace

std::vector<double> moving_average(const std::vector<double>& values, int window) {
  if (window < 1) throw std::invalid_argument(fmt::format("moving average window {} must be >= 1", window));
  std::vector<double> out(values.size());
  double sum = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    sum += values[i];
    if (i >= static_cast<size_t>(window)) sum -= values[i - window];
    out[i] = sum / static_cast<double>(std::min(i + 1, static_cast<size_t>(window)));
  }
  return out;
}

void plot_training_curves(const std::vector<CurveSeries>& series, const std::string& png_path,
                          const CurveOptions& options) {
  if (series.empty()) throw std::invalid_argument("plot_training_curves: no runs to plot");
  const std::string gnuplot = require_executable("gnuplot", "gnuplot-nox");
  const std::string base = stem(png_path);

  std::string score_plot, success_plot;
  for (size_t i = 0; i < series.size(); ++i) {
    const auto& s = series[i];
    if (s.episodes.empty()) throw std::invalid_argument(fmt::format("run '{}' has no training episodes to plot", s.label));
    std::vector<double> score, success;
    for (const auto& e : s.episodes) {
      score.push_back(e.return_R1);
      success.push_back(e.success ? 100.0 : 0.0);
    }
    const auto score_avg = moving_average(score, options.window);
    const auto success_avg = moving_average(success, options.window);
    const std::string data_path = fmt::format("{}-{}.dat", base, i);
    std::ostringstream data;
    data << "# episode  score(R1)  score_moving_avg  success_rate_percent(window " << options.window << ")\n";
    for (size_t k = 0; k < score.size(); ++k)
      data << fmt::format("{} {} {} {}\n", s.episodes[k].episode, score[k], score_avg[k], success_avg[k]);
    write_file_atomic(data_path, data.str());

    // Per-episode scores faint (alpha 0xB0 of 0xFF transparent), averages bold.
    const std::string c = colour(i);
    const std::string faint = "#B0" + c.substr(1);
    score_plot += fmt::format("{}{} using 1:2 with lines lw 1 lc rgb '{}' notitle, \\\n  {} using 1:3 with lines lw 2.5 lc rgb '{}' title {}",
                              i ? ", \\\n  " : "", quoted(data_path), faint, quoted(data_path), c,
                              quoted(s.label));
    success_plot += fmt::format("{}{} using 1:4 with lines lw 2.5 lc rgb '{}' title {}", i ? ", \\\n  " : "",
                                quoted(data_path), c, quoted(s.label));
  }

  const std::string script_path = base + ".gp";
  std::ostringstream script;
  script << "# Written by comorph report; run `gnuplot " << script_path << "` to redraw.\n"
         << fmt::format("set terminal {} size {},{}\n", options.terminal, options.width_px, options.height_px)
         << "set output " << quoted(png_path) << "\n"
         << "set datafile commentschars '#'\n"
         << "set grid\nset key left top opaque\n"
         << "set multiplot layout 2,1 title " << quoted(options.title) << "\n"
         << "set xlabel 'episode'\n"
         << "set ylabel 'score (return of R1)'\n"
         << fmt::format("set title 'Score per episode (faint) and its moving average over {} episodes'\n", options.window)
         << "plot " << score_plot << "\n"
         << "set ylabel 'success rate (%)'\nset yrange [0:100]\n"
         << fmt::format("set title 'Success rate over the last {} episodes'\n", options.window)
         << "plot " << success_plot << "\n"
         << "unset multiplot\nunset output\n";
  write_file_atomic(script_path, script.str());
  run_tool({gnuplot, script_path});
  std::ifstream png(png_path, std::ios::binary | std::ios::ate);
  if (!png || png.tellg() <= 0) throw std::runtime_error(fmt::format("gnuplot wrote no image to {}", png_path));
}

}  // namespace comorph::report
