#include "Plots.h"

#include <plstream.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

namespace cape::demo {

namespace {

bool hasPngCairo() {
  // plgFileDevs fills caller-owned arrays; `count` says how long they are on the way in.
  const char* menuStore[128] = {};
  const char* nameStore[128] = {};
  const char** menu = menuStore;
  const char** names = nameStore;
  int count = 128;
  plgFileDevs(&menu, &names, &count);
  for (int i = 0; i < count; ++i)
    if (std::strcmp(names[i], "pngcairo") == 0) return true;
  return false;
}

}  // namespace

bool plotLines(const std::filesystem::path& file, const std::string& title, const std::string& xLabel,
               const std::string& yLabel, const std::vector<Series>& series, std::string& error) {
  if (!hasPngCairo()) {
    error = "PLplot has no pngcairo driver (install plplot-driver-cairo)";
    return false;
  }
  if (!std::ofstream(file)) {  // PLplot would exit the process on a file it cannot open
    error = "cannot write " + file.string();
    return false;
  }
  double x0 = 0.0, x1 = 1.0, y0 = 0.0, y1 = 0.0;
  bool any = false;
  for (const Series& s : series)
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x0 = any ? std::min(x0, s.x[i]) : s.x[i];
      x1 = any ? std::max(x1, s.x[i]) : s.x[i];
      y1 = std::max(y1, s.y[i]);
      y0 = std::min(y0, s.y[i]);
      any = true;
    }
  if (!(x1 > x0)) x1 = x0 + 1.0;
  if (!(y1 > y0)) y1 = y0 + 1.0;
  y1 += 0.08 * (y1 - y0);  // head room for the legend

  plstream pls;
  pls.sdev("pngcairo");
  pls.sfnam(file.c_str());
  pls.setopt("geometry", "960x540");
  // Colour map 0: white background, black axes, then one colour per series.
  pls.scol0(0, 255, 255, 255);
  pls.scol0(1, 0, 0, 0);
  const int palette[][3] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {148, 103, 189}, {255, 127, 14}};
  for (int k = 0; k < 5; ++k) pls.scol0(2 + k, palette[k][0], palette[k][1], palette[k][2]);
  pls.init();
  pls.col0(1);
  pls.env(x0, x1, y0, y1, 0, 0);
  pls.lab(xLabel.c_str(), yLabel.c_str(), title.c_str());
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    const int n = static_cast<int>(std::min(s.x.size(), s.y.size()));
    pls.col0(2 + static_cast<int>(k % 5));
    pls.width(2.0);
    if (n > 0) pls.line(n, s.x.data(), s.y.data());
    pls.mtex("t", -1.5 * static_cast<double>(k + 1), 0.98, 1.0, s.name.c_str());
  }
  return true;  // the stream is finished and the file closed when `pls` goes out of scope
}

}  // namespace cape::demo
