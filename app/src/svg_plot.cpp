#include "gabarit/app/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "gabarit/app/error.hpp"

namespace gabarit::app::svg {
namespace {

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}

std::string head(int w, int h, const std::string& title) {
  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h << "' font-family='sans-serif' font-size='11'>\n"
    << "<rect width='100%' height='100%' fill='white'/>\n"
    << "<text x='" << w / 2 << "' y='18' text-anchor='middle' font-size='14'>" << esc(title) << "</text>\n";
  return o.str();
}

const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};

std::string num(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

}  // namespace

std::string heatmap(const std::string& title, const std::string& x_title, const std::vector<std::string>& x_labels,
                    const std::string& y_title, const std::vector<std::string>& y_labels,
                    const std::vector<std::vector<double>>& values, double max_value) {
  const int cw = 56, ch = 18, left = 70, top = 40;
  const int w = left + cw * static_cast<int>(x_labels.size()) + 20;
  const int h = top + ch * static_cast<int>(y_labels.size()) + 50;
  std::ostringstream o;
  o << head(w, h, title);
  for (std::size_t r = 0; r < y_labels.size(); ++r) {
    o << "<text x='" << left - 6 << "' y='" << top + ch * static_cast<int>(r) + 13 << "' text-anchor='end'>" << esc(y_labels[r]) << "</text>\n";
    for (std::size_t c = 0; c < x_labels.size(); ++c) {
      const double v = values[r][c];
      const double f = max_value > 0 ? std::clamp(v / max_value, 0.0, 1.0) : 0.0;
      const int red = 255 - static_cast<int>(f * 115), gb = 255 - static_cast<int>(std::sqrt(f) * 255);
      o << "<rect x='" << left + cw * static_cast<int>(c) << "' y='" << top + ch * static_cast<int>(r) << "' width='" << cw
        << "' height='" << ch << "' fill='rgb(" << red << "," << gb << "," << gb << ")' stroke='#ddd'/>"
        << "<text x='" << left + cw * static_cast<int>(c) + cw / 2 << "' y='" << top + ch * static_cast<int>(r) + 13
        << "' text-anchor='middle' fill='" << (f > 0.6 ? "white" : "black") << "'>" << num(v) << "</text>\n";
    }
  }
  for (std::size_t c = 0; c < x_labels.size(); ++c) {
    o << "<text x='" << left + cw * static_cast<int>(c) + cw / 2 << "' y='" << top + ch * static_cast<int>(y_labels.size()) + 14
      << "' text-anchor='middle'>" << esc(x_labels[c]) << "</text>\n";
  }
  o << "<text x='" << left + cw * static_cast<int>(x_labels.size()) / 2 << "' y='" << h - 10 << "' text-anchor='middle'>" << esc(x_title) << "</text>\n";
  o << "<text x='14' y='" << top + ch * static_cast<int>(y_labels.size()) / 2 << "' text-anchor='middle' transform='rotate(-90 14 "
    << top + ch * static_cast<int>(y_labels.size()) / 2 << ")'>" << esc(y_title) << "</text>\n</svg>\n";
  return o.str();
}

std::string lines(const std::string& title, const std::string& x_title, const std::string& y_title,
                  const std::vector<Series>& series, bool log_x, bool log_y) {
  const int w = 640, h = 400, left = 70, right = 170, top = 36, bottom = 50;
  const auto tx = [&](double v) { return log_x ? std::log10(std::max(v, 1e-9)) : v; };
  const auto ty = [&](double v) { return log_y ? std::log10(std::max(v, 0.5)) : v; };
  double x0 = 1e300, x1 = -1e300, y0 = log_y ? ty(1) : 0, y1 = -1e300;
  for (const Series& s : series)
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      x0 = std::min(x0, tx(s.x[i]));
      x1 = std::max(x1, tx(s.x[i]));
      y0 = std::min(y0, ty(s.y[i]));
      y1 = std::max(y1, ty(s.y[i]));
    }
  if (x1 <= x0) x1 = x0 + 1;
  if (y1 <= y0) y1 = y0 + 1;
  const auto px = [&](double v) { return left + (tx(v) - x0) / (x1 - x0) * (w - left - right); };
  const auto py = [&](double v) { return h - bottom - (ty(v) - y0) / (y1 - y0) * (h - top - bottom); };
  std::ostringstream o;
  o << head(w, h, title);
  o << "<rect x='" << left << "' y='" << top << "' width='" << w - left - right << "' height='" << h - top - bottom
    << "' fill='none' stroke='black'/>\n";
  for (int i = 0; i <= 4; ++i) {
    const double xv = x0 + (x1 - x0) * i / 4, yv = y0 + (y1 - y0) * i / 4;
    const double xl = log_x ? std::pow(10, xv) : xv, yl = log_y ? std::pow(10, yv) : yv;
    const double gx = left + (w - left - right) * i / 4.0, gy = h - bottom - (h - top - bottom) * i / 4.0;
    o << "<text x='" << gx << "' y='" << h - bottom + 14 << "' text-anchor='middle'>" << num(std::round(xl * 1000) / 1000) << "</text>\n";
    o << "<text x='" << left - 4 << "' y='" << gy + 4 << "' text-anchor='end'>" << num(std::round(yl * 100) / 100) << "</text>\n";
    o << "<line x1='" << left << "' x2='" << w - right << "' y1='" << gy << "' y2='" << gy << "' stroke='#eee'/>\n";
  }
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    o << "<polyline fill='none' stroke='" << kColours[k % 8] << "' stroke-width='1.5' points='";
    for (std::size_t i = 0; i < s.x.size(); ++i) o << px(s.x[i]) << ',' << py(s.y[i]) << ' ';
    o << "'/>\n<text x='" << w - right + 8 << "' y='" << top + 14 * (static_cast<int>(k) + 1) << "' fill='" << kColours[k % 8] << "'>"
      << esc(s.label) << "</text>\n";
  }
  o << "<text x='" << (left + w - right) / 2 << "' y='" << h - 12 << "' text-anchor='middle'>" << esc(x_title) << "</text>\n";
  o << "<text x='14' y='" << (top + h - bottom) / 2 << "' text-anchor='middle' transform='rotate(-90 14 " << (top + h - bottom) / 2
    << ")'>" << esc(y_title) << "</text>\n</svg>\n";
  return o.str();
}

std::string bars(const std::string& title, const std::string& value_title, const std::vector<std::string>& labels,
                 const std::vector<double>& values) {
  const int left = 330, w = 820, bh = 20, top = 36;
  const int h = top + bh * static_cast<int>(labels.size()) + 40;
  double lo = 1e300, hi = 0;
  for (double v : values) lo = std::min(lo, v), hi = std::max(hi, v);
  const double l0 = std::floor(std::log10(std::max(lo, 1e-3))), l1 = std::ceil(std::log10(std::max(hi, 1e-3))) + 0.01;
  const auto bx = [&](double v) { return (std::log10(std::max(v, 1e-3)) - l0) / (l1 - l0) * (w - left - 90); };
  std::ostringstream o;
  o << head(w, h, title);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const int y = top + bh * static_cast<int>(i);
    o << "<text x='" << left - 6 << "' y='" << y + 14 << "' text-anchor='end'>" << esc(labels[i]) << "</text>"
      << "<rect x='" << left << "' y='" << y + 3 << "' width='" << bx(values[i]) << "' height='" << bh - 6 << "' fill='"
      << kColours[i % 8] << "'/><text x='" << left + bx(values[i]) + 4 << "' y='" << y + 14 << "'>" << num(std::round(values[i] * 10) / 10)
      << "</text>\n";
  }
  o << "<text x='" << left << "' y='" << h - 10 << "'>" << esc(value_title) << " (log scale, 10^" << l0 << " .. 10^" << l1 << ")</text>\n</svg>\n";
  return o.str();
}

void write(const std::string& path, const std::string& svg) {
  std::ofstream f(path);
  f << svg;
  if (!f.flush()) throw app::Error(path + ": write failed");
}

}  // namespace gabarit::app::svg
