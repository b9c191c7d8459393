// Line charts as PNG, drawn by PLplot (Debian's libplplot-dev, through its cairo driver): what cape_compare
// plots over a run (strain, penetration, frame time per solver).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace cape::demo {

struct Series {
  std::string name;
  std::vector<double> x, y;
};

/// Writes one chart with a line per series and a legend. False and a one-line reason if PLplot or its cairo
/// driver is missing, or the file cannot be written.
bool plotLines(const std::filesystem::path& file, const std::string& title, const std::string& xLabel,
               const std::string& yLabel, const std::vector<Series>& series, std::string& error);

}  // namespace cape::demo
