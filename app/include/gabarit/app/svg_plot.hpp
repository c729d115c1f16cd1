// Minimal SVG charts for reports (gabarit bench, gabarit tables analyse; no plotting dependency): a heat
// map with numbers in its cells, a line chart, and horizontal bars.
#pragma once

#include <string>
#include <vector>

namespace gabarit::app::svg {

struct Series {
  std::string label;
  std::vector<double> x, y;
};

// values[row][col]; rows are drawn top to bottom. Colour runs from white (0)
// to dark red (max_value).
std::string heatmap(const std::string& title, const std::string& x_title, const std::vector<std::string>& x_labels,
                    const std::string& y_title, const std::vector<std::string>& y_labels,
                    const std::vector<std::vector<double>>& values, double max_value);

std::string lines(const std::string& title, const std::string& x_title, const std::string& y_title,
                  const std::vector<Series>& series, bool log_x, bool log_y);

// Horizontal bars on a log10 axis (timings span decades).
std::string bars(const std::string& title, const std::string& value_title, const std::vector<std::string>& labels,
                 const std::vector<double>& values);

void write(const std::string& path, const std::string& svg);

}  // namespace gabarit::app::svg
