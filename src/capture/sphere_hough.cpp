// Step 2 of the sphere's detection without a mask (the overview is at the
// top of sphere_detect.cpp): the candidate circles, cv::HoughCircles on the
// 8-bit rendition, re-ranked by their radial edge support beyond chance.
// OpenCV coordinates throughout.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/vec.h"
#include "sphere_detect_internal.hpp"

namespace cf_sphere_cv {

namespace {

constexpr int kMaxHoughSize = 1200;        // px: larger images are searched downscaled
constexpr size_t kMaxHoughCircles = 1000;  // ranked by their support
constexpr size_t kMaxCandidates = 16;      // Hough circles refined

// How far from a circle of radius `rad` its support looks: max(2, r/16)
// px, since a sphere seen off-axis is an ellipse.
int support_reach(double rad) {
  return std::max(2, static_cast<int>(std::lround(rad / 16)));
}

// The fraction of directions around the circle with an edge pixel within
// `reach` px of it (radially) whose gradient is within about 30° of radial.
double support(const Renditions &r, double cx, double cy, double rad, int reach) {
  int n = std::max(16, static_cast<int>(CF_PI * rad));  // a direction every 2 px
  int hits = 0;
  double step_c = std::cos(2 * CF_PI / n), step_s = std::sin(2 * CF_PI / n);
  double c = 1, s = 0;
  for (int i = 0; i < n; ++i) {
    if (i > 0) {  // rotate by 2π/n
      double next_c = c * step_c - s * step_s;
      s = s * step_c + c * step_s;
      c = next_c;
    }
    for (int t = -reach; t <= reach; ++t) {
      double fx = cx + (rad + t) * c + 0.5, fy = cy + (rad + t) * s + 0.5;
      if (fx < 0 || fy < 0 || fx >= r.edge_map.cols || fy >= r.edge_map.rows) continue;
      int x = static_cast<int>(fx), y = static_cast<int>(fy);  // nearest pixel
      if (!r.edge_map(y, x)) continue;
      double gx = r.gx(y, x), gy = r.gy(y, x);
      if (std::fabs(gx * c + gy * s) >= 0.85 * std::hypot(gx, gy)) {
        ++hits;
        break;
      }
    }
  }
  return static_cast<double>(hits) / n;
}

}  // namespace

std::vector<Ellipse> hough_candidates(const Renditions &r, const SearchRange &range, double canny) {
  cv::Rect roi(0, 0, r.search.cols, r.search.rows);
  if (range.has_centre) {
    double reach = range.max_offset + range.max_radius + 4 * kSearchSigma + 4;
    cv::Rect near(static_cast<int>(std::floor(range.cx - reach)),
                  static_cast<int>(std::floor(range.cy - reach)),
                  static_cast<int>(std::ceil(2 * reach)) + 1,
                  static_cast<int>(std::ceil(2 * reach)) + 1);
    roi &= near;
  }
  std::vector<Ellipse> out;
  if (roi.width < 8 || roi.height < 8) return out;
  cv::Mat1b view = r.search(roi);
  int factor = std::max(1, (std::max(view.cols, view.rows) + kMaxHoughSize - 1) / kMaxHoughSize);
  cv::Mat1b small;
  if (factor > 1)
    cv::resize(view, small, cv::Size(view.cols / factor, view.rows / factor), 0, 0, cv::INTER_AREA);
  else
    small = view;
  // dst pixel i covers src [i f, (i + 1) f): its centre is at src i f + (f − 1)/2.
  double f = factor, shift = 0.5 * (factor - 1);
  int min_r = std::max(2, static_cast<int>(std::floor(range.min_radius / f)));
  int max_r = std::max(min_r + 1, static_cast<int>(std::ceil(range.max_radius / f)));
  double dp = 2.0;
  double votes = std::max(10.0, 0.25 * 2 * CF_PI * min_r / dp);
  std::vector<cv::Vec3f> circles;
  cv::HoughCircles(small, circles, cv::HOUGH_GRADIENT, dp, std::max(2.0, 0.5 * min_r), canny, votes,
                   min_r, max_r);
  // Hough's votes favour large circles in texture; rank the circles by how
  // far their support (the fraction of directions around each with a
  // radial edge pixel near it) exceeds chance, in binomial standard
  // deviations (an "a contrario" test: Desolneux, Moisan & Morel 2008).
  // Chance is the larger of the support of circles 3 search widths larger
  // and smaller (the clutter there) and the median support of all the
  // circles (the clutter of the image), at least 2%.
  struct Scored {
    Ellipse circle;
    double support, local_chance;
  };
  std::vector<Scored> scored;
  std::vector<double> supports;
  if (circles.size() > kMaxHoughCircles) circles.resize(kMaxHoughCircles);  // most votes first
  for (const cv::Vec3f &c : circles) {
    double cx = c[0] * f + shift + roi.x, cy = c[1] * f + shift + roi.y, rad = c[2] * f;
    if (range.has_centre && std::hypot(cx - range.cx, cy - range.cy) > range.max_offset) continue;
    int reach = support_reach(rad);
    double local = 0.5 * (support(r, cx, cy, rad + 3 * reach, reach) +
                          support(r, cx, cy, std::max(2.0, rad - 3 * reach), reach));
    scored.push_back({circle(cx, cy, rad), support(r, cx, cy, rad, reach), local});
    supports.push_back(scored.back().support);
  }
  double image_chance = median(supports);
  std::vector<std::pair<double, Ellipse>> ranked;
  for (const Scored &c : scored) {
    double n = std::max(16.0, CF_PI * c.circle.a);
    double chance = std::min(std::max({c.local_chance, image_chance, 0.02}), 0.95);
    double z = (c.support - chance) * std::sqrt(n / (chance * (1 - chance)));
    ranked.push_back({-z, c.circle});
  }
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto &p, const auto &q) { return p.first < q.first; });
  for (const auto &item : ranked) {
    const Ellipse &c = item.second;
    bool seen = false;  // a near duplicate refines to the same outline
    for (const Ellipse &e : out)
      seen = seen || (std::hypot(e.cx - c.cx, e.cy - c.cy) < 0.05 * c.a + 1 &&
                      std::fabs(e.a - c.a) < 0.05 * c.a + 1);
    if (!seen) out.push_back(c);
    if (out.size() >= kMaxCandidates) break;
  }
  return out;
}

}  // namespace cf_sphere_cv
