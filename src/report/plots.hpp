// Training curves as in the paper's Fig. 9, drawn by gnuplot: score per
// episode with its moving average, and the success rate over a sliding window,
// one curve per run. We write the data and a gnuplot script next to the PNG
// (so a researcher can restyle and re-run it) and run `gnuplot` on it.
#pragma once

#include <string>
#include <vector>

#include "report/episode_record.hpp"

namespace comorph::report {

struct CurveOptions {
  int window = 100;                 // episodes in the moving average and the success window
  int width_px = 1000;              // PNG width, pixels
  int height_px = 700;              // PNG height, pixels
  std::string terminal = "pngcairo";  // gnuplot terminal: pngcairo (Debian's gnuplot-nox has it) or png
  std::string title = "Training curves";
};

// One run's training episodes, labelled in the legend.
struct CurveSeries {
  std::string label;
  std::vector<EpisodeRecord> episodes;  // in episode order
};

// Trailing means over the last `window` values (fewer at the start).
std::vector<double> moving_average(const std::vector<double>& values, int window);

// Writes `png_path` plus `<png_path minus .png>.gp` and `...-<i>.dat`
// (columns: episode, score, score moving average, success rate in percent over
// the window). Throws when gnuplot is not installed (naming the package), when
// a series is empty, or when gnuplot fails.
void plot_training_curves(const std::vector<CurveSeries>& series, const std::string& png_path,
                          const CurveOptions& options = {});

}  // namespace comorph::report
