// Steps 1 and 3 of the sphere's detection without a mask (the overview is
// at the top of sphere_detect.cpp): the renditions of the image and its
// Canny threshold; the refinement of a candidate outline (sub-pixel edge
// points, the outline's edge per direction, the ellipse or circle fit with
// iterative rejection, the coverage beyond chance); and the outline
// geometry the detection's files share. OpenCV coordinates throughout.
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

constexpr double kEdgeSigma = 1.0;     // px, blur of the linear grey
constexpr double kGamma = 1.0 / 2.2;   // 8-bit rendition for the search only
constexpr double kPercentile = 0.995;  // of grey, mapped to 1
constexpr double kMinAxisRatio = 0.5;  // b / a of a plausible sphere outline

// A dark limb's outer edge (outline_edge): within this band outside its
// inner edge and at least this fraction as strong. On clayfit synth
// --silhouettes (r = 157 px, exact Fresnel) the two edges lie 3.5-4.3 px
// apart, the outer 0.65-0.8 as strong; taking the inner one put the outline
// 2.5-3 px inside on the flash side of 4 views in 12 and the triangulated
// centre 0.007-0.013 R off over seeds 1-10 (0.0018-0.0093 R with the rule).
constexpr double kLimbBandOfRadius = 0.03;  // of the radius
constexpr double kLimbBandMin = 3.0;        // px
constexpr double kLimbMinGap = 1.0;         // px: closer is the same edge
constexpr double kLimbEdgeRatio = 0.5;

// a >= b and angle in (−π/2, π/2].
Ellipse normalized(double cx, double cy, double a, double b, double angle) {
  Ellipse e;
  e.cx = cx;
  e.cy = cy;
  if (b > a) {
    std::swap(a, b);
    angle += 0.5 * CF_PI;
  }
  angle = std::fmod(angle, CF_PI);
  if (angle <= -0.5 * CF_PI) angle += CF_PI;
  if (angle > 0.5 * CF_PI) angle -= CF_PI;
  e.a = a;
  e.b = b;
  e.angle = angle;
  return e;
}

}  // namespace

Ellipse circle(double cx, double cy, double r) {
  return normalized(cx, cy, r, r, 0.0);
}

Ellipse from_rotated_rect(const cv::RotatedRect &box) {
  return normalized(box.center.x, box.center.y, 0.5 * box.size.width, 0.5 * box.size.height,
                    box.angle * CF_PI / 180.0);
}

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  return values[mid];
}

namespace {

bool plausible(const Ellipse &e) {
  return std::isfinite(e.cx) && std::isfinite(e.cy) && std::isfinite(e.a) &&
         std::isfinite(e.angle) && e.b > 0 && e.a >= e.b && e.b >= kMinAxisRatio * e.a;
}

// Point in the ellipse's frame, scaled to the unit circle.
void ellipse_frame(const Ellipse &e, double x, double y, double *u, double *v) {
  double c = std::cos(e.angle), s = std::sin(e.angle);
  double dx = x - e.cx, dy = y - e.cy;
  *u = (c * dx + s * dy) / e.a;
  *v = (-s * dx + c * dy) / e.b;
}

// Signed distance (outside positive) from (x, y) to the ellipse, to first
// order in its eccentricity: |p − c| (1 − 1/ρ), ρ the ellipse's level.
double ellipse_residual(const Ellipse &e, double x, double y) {
  double u, v;
  ellipse_frame(e, x, y, &u, &v);
  double rho = std::sqrt(u * u + v * v);
  double dist = std::hypot(x - e.cx, y - e.cy);
  if (!(rho > 0)) return -std::min(e.a, e.b);
  return dist * (1.0 - 1.0 / rho);
}

// Unit outward normal of the ellipse's level curve through (x, y).
void ellipse_normal(const Ellipse &e, double x, double y, double n[2]) {
  double u, v;
  ellipse_frame(e, x, y, &u, &v);
  double gu = u / e.a, gv = v / e.b;  // ∇ρ²/2 in the rotated frame
  double c = std::cos(e.angle), s = std::sin(e.angle);
  double nx = c * gu - s * gv, ny = s * gu + c * gv;
  double len = std::hypot(nx, ny);
  n[0] = len > 0 ? nx / len : 1.0;
  n[1] = len > 0 ? ny / len : 0.0;
}

// Direction bin of (x, y) around the ellipse (its parametric angle).
int direction_bin(const Ellipse &e, double x, double y, int bins) {
  double u, v;
  ellipse_frame(e, x, y, &u, &v);
  double t = std::atan2(v, u) / (2.0 * CF_PI) + 0.5;  // [0, 1]
  int k = static_cast<int>(t * bins);
  return std::min(std::max(k, 0), bins - 1);
}

// The q-quantile of a float image (subsampled to about a million values).
double quantile(const cv::Mat1f &m, double q) {
  size_t total = m.total();
  size_t stride = std::max<size_t>(1, total / 1000000);
  std::vector<float> values;
  values.reserve(total / stride + 1);
  const float *data = m.ptr<float>(0);  // continuous
  for (size_t k = 0; k < total; k += stride) values.push_back(data[k]);
  size_t idx =
      std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(idx), values.end());
  return values[idx];
}

double bilinear(const cv::Mat1f &m, double x, double y) {
  x = std::min(std::max(x, 0.0), static_cast<double>(m.cols - 1));
  y = std::min(std::max(y, 0.0), static_cast<double>(m.rows - 1));
  int x0 = std::min(static_cast<int>(x), m.cols - 2 < 0 ? 0 : m.cols - 2);
  int y0 = std::min(static_cast<int>(y), m.rows - 2 < 0 ? 0 : m.rows - 2);
  int x1 = std::min(x0 + 1, m.cols - 1), y1 = std::min(y0 + 1, m.rows - 1);
  double fx = x - x0, fy = y - y0;
  return (1 - fy) * ((1 - fx) * m(y0, x0) + fx * m(y0, x1)) +
         fy * ((1 - fx) * m(y1, x0) + fx * m(y1, x1));
}

cv::Mat1f grey_of(const cf_image &image) {
  cv::Mat1f grey(image.height, image.width);
  int used = image.channels >= 3 ? 3 : 1;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float *p = image.pixels + (static_cast<size_t>(y) * static_cast<size_t>(image.width) +
                                       static_cast<size_t>(x)) *
                                          static_cast<size_t>(image.channels);
      double sum = 0;
      for (int c = 0; c < used; ++c)
        if (std::isfinite(p[c])) sum += p[c];
      grey(y, x) = static_cast<float>(sum / used);
    }
  return grey;
}

}  // namespace

bool make_renditions(const cf_image &image, Renditions *r) {
  cv::Mat1f grey = grey_of(image);
  double scale = quantile(grey, kPercentile);
  if (!(scale > 0)) {
    double max_value = 0;
    cv::minMaxLoc(grey, nullptr, &max_value);
    scale = max_value;
  }
  if (!(scale > 0) || !std::isfinite(scale)) return false;
  grey *= 1.0 / scale;
  cv::GaussianBlur(grey, r->linear, cv::Size(0, 0), kEdgeSigma, kEdgeSigma, cv::BORDER_REPLICATE);
  cv::Sobel(r->linear, r->gx, CV_32F, 1, 0, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
  cv::Sobel(r->linear, r->gy, CV_32F, 0, 1, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
  cv::magnitude(r->gx, r->gy, r->mag);
  r->median_mag = quantile(r->mag, 0.5);

  cv::Mat1f encoded;
  cv::min(cv::max(grey, 0.0), 1.0, encoded);
  cv::pow(encoded, kGamma, encoded);
  cv::GaussianBlur(encoded, encoded, cv::Size(0, 0), kSearchSigma, kSearchSigma,
                   cv::BORDER_REPLICATE);
  encoded.convertTo(r->search, CV_8U, 255.0);
  return true;
}

double canny_high(const cv::Mat1b &search) {
  cv::Mat1f dx, dy, mag;
  cv::Sobel(search, dx, CV_32F, 1, 0, 3);
  cv::Sobel(search, dy, CV_32F, 0, 1, 3);
  cv::magnitude(dx, dy, mag);
  double high = std::max(0.4 * quantile(mag, 0.99), 4.0 * quantile(mag, 0.5));
  return std::min(std::max(high, 12.0), 600.0);
}

namespace {

// Move an edge pixel along its gradient to the maximum of the gradient
// magnitude (parabola through three samples; Devernay 1995). False if the
// maximum is not within 2 px.
bool subpixel_edge(const Renditions &r, int px, int py, EdgePoint *out) {
  double gx = r.gx(py, px), gy = r.gy(py, px);
  double len = std::hypot(gx, gy);
  if (!(len > 0)) return false;
  double dx = gx / len, dy = gy / len;
  auto mag_at = [&](double t) { return bilinear(r.mag, px + t * dx, py + t * dy); };
  double t0 = 0, m0 = mag_at(0);
  for (int step = 0; step < 2; ++step) {  // climb to the local maximum
    double mp = mag_at(t0 + 1), mm = mag_at(t0 - 1);
    if (mp > m0 && mp >= mm) {
      t0 += 1;
      m0 = mp;
    } else if (mm > m0) {
      t0 -= 1;
      m0 = mm;
    } else {
      break;
    }
  }
  double mp = mag_at(t0 + 1), mm = mag_at(t0 - 1);
  double curvature = mp - 2 * m0 + mm;
  if (!(curvature < 0) || mp > m0 || mm > m0) return false;
  double offset = t0 + 0.5 * (mm - mp) / curvature;
  if (std::fabs(offset) > 2.0) return false;
  out->x = px + offset * dx;
  out->y = py + offset * dy;
  out->strength = m0 - 0.125 * (mm - mp) * (mm - mp) / curvature;
  return true;
}

// Kasa's algebraic circle fit (Kasa 1976): x² + y² + D x + E y + F = 0.
bool fit_circle(const std::vector<EdgePoint> &pts, Ellipse *out) {
  if (pts.size() < 3) return false;
  double mx = 0, my = 0;
  for (const EdgePoint &p : pts) {
    mx += p.x;
    my += p.y;
  }
  mx /= static_cast<double>(pts.size());
  my /= static_cast<double>(pts.size());
  cv::Matx33d a = cv::Matx33d::zeros();
  cv::Vec3d b(0, 0, 0);
  for (const EdgePoint &p : pts) {
    double x = p.x - mx, y = p.y - my;
    cv::Vec3d row(x, y, 1.0);
    double rhs = -(x * x + y * y);
    for (int i = 0; i < 3; ++i) {
      b[i] += row[i] * rhs;
      for (int j = 0; j < 3; ++j) a(i, j) += row[i] * row[j];
    }
  }
  cv::Vec3d s;
  if (!cv::solve(a, b, s, cv::DECOMP_CHOLESKY)) return false;
  double cx = -0.5 * s[0], cy = -0.5 * s[1];
  double r2 = cx * cx + cy * cy - s[2];
  if (!(r2 > 0)) return false;
  *out = circle(cx + mx, cy + my, std::sqrt(r2));
  return true;
}

// An ellipse through the points (a circle if the ellipse is implausible).
bool fit_outline(const std::vector<EdgePoint> &pts, Ellipse *out) {
  if (pts.size() >= 6) {
    std::vector<cv::Point2f> p2;
    p2.reserve(pts.size());
    for (const EdgePoint &p : pts)
      p2.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    Ellipse e = from_rotated_rect(cv::fitEllipse(p2));
    if (plausible(e)) {
      *out = e;
      return true;
    }
  }
  return fit_circle(pts, out);
}

// An edge point near an ellipse: its signed distance from it (outside
// positive) and whether the image is brighter on its outer side.
struct Candidate {
  EdgePoint point;
  double residual;
  bool brighter_outside;
};

// Edge points within `band` of the ellipse, or up to `limb` px beyond it
// outside (only ever the outer side of a dark limb, below), whose gradient
// is within 30° of its normal; by direction bin (about 2 px of outline).
std::vector<std::vector<Candidate>> edge_candidates(const Renditions &r, const Ellipse &e,
                                                    double band, double limb, int bins) {
  std::vector<std::vector<Candidate>> per_bin(static_cast<size_t>(bins));
  double reach = e.a + band + limb + 2;
  for (const cv::Point &q : r.edges) {
    if (std::fabs(q.x - e.cx) > reach || std::fabs(q.y - e.cy) > reach) continue;
    double res = ellipse_residual(e, q.x, q.y);
    if (res < -band - 2 || res > band + limb + 2) continue;
    EdgePoint p;
    if (!subpixel_edge(r, q.x, q.y, &p)) continue;
    res = ellipse_residual(e, p.x, p.y);
    if (res < -band || res > band + limb) continue;
    double n[2];
    ellipse_normal(e, p.x, p.y, n);
    double gx = r.gx(q.y, q.x), gy = r.gy(q.y, q.x);
    double along = gx * n[0] + gy * n[1];
    if (std::fabs(along) < std::cos(30.0 * CF_PI / 180.0) * std::hypot(gx, gy)) continue;
    per_bin[static_cast<size_t>(direction_bin(e, p.x, p.y, bins))].push_back({p, res, along > 0});
  }
  return per_bin;
}

// The edge of one direction bin taken for the outline: the strongest within
// `band`, unless it is the inner side of a dark limb, brighter inside, with
// an edge brighter outside at most `limb` px further out and at least
// kLimbEdgeRatio as strong: then the strongest such outer edge. (A limb
// against a brighter background is a dark band, its shading and its
// Fresnel transmission falling to zero at grazing; in an sRGB rendition its
// inner side is often the stronger edge.) bin.size() if none is in the band.
size_t outline_edge(const std::vector<Candidate> &bin, double band, double limb) {
  size_t best = bin.size();
  for (size_t k = 0; k < bin.size(); ++k)
    if (bin[k].residual <= band &&
        (best == bin.size() || bin[k].point.strength > bin[best].point.strength))
      best = k;
  if (best == bin.size() || bin[best].brighter_outside) return best;
  const Candidate &inner = bin[best];
  size_t outer = best;
  for (size_t k = 0; k < bin.size(); ++k) {
    const Candidate &c = bin[k];
    double beyond = c.residual - inner.residual;
    if (c.brighter_outside && beyond > kLimbMinGap && beyond <= limb &&
        c.point.strength >= kLimbEdgeRatio * inner.point.strength &&
        (outer == best || c.point.strength > bin[outer].point.strength))
      outer = k;
  }
  return outer;
}

// The outline's edge points near the ellipse: per direction bin the edge
// taken for the outline (outline_edge) and those of its polarity within
// 1 px of it across the outline; within `band` of the ellipse, or for a dark
// limb's outer edge up to the limb band beyond it.
std::vector<EdgePoint> collect(const Renditions &r, const Ellipse &e, double band) {
  int bins = std::max(32, static_cast<int>(CF_PI * (e.a + e.b) / 2.0));
  double limb = std::max(kLimbBandMin, kLimbBandOfRadius * 0.5 * (e.a + e.b));
  std::vector<EdgePoint> kept;
  for (const std::vector<Candidate> &bin : edge_candidates(r, e, band, limb, bins)) {
    size_t k = outline_edge(bin, band, limb);
    if (k == bin.size()) continue;
    const Candidate &edge = bin[k];
    double reach = edge.residual <= band ? band : band + limb;
    for (const Candidate &c : bin)
      if (std::fabs(c.residual - edge.residual) <= 1.0 && c.residual <= reach &&
          c.brighter_outside == edge.brighter_outside)
        kept.push_back(c.point);
  }
  return kept;
}

// Iterative rejection with a shrinking threshold: from `guess`, keep the
// points within the threshold of the current ellipse and refit; the
// threshold starts at `band` and shrinks by 0.6 a round down to `floor`
// (so that clutter far from the outline goes first and cannot drag the
// fit), then it is 3 robust sigmas (1.4826 × the median absolute
// residual), at least 0.5 px and at most `floor`, until the set stops
// changing.
Fit robust_fit(const std::vector<EdgePoint> &pts, const Ellipse &guess, double band, double floor) {
  Fit fit;
  fit.band = band;
  Ellipse current = guess;
  std::vector<char> in(pts.size(), 0), next(pts.size(), 0);
  std::vector<EdgePoint> inliers;
  double threshold = band;
  bool annealed = false;
  for (int round = 0; round < 30; ++round) {
    inliers.clear();
    for (size_t k = 0; k < pts.size(); ++k) {
      next[k] = std::fabs(ellipse_residual(current, pts[k].x, pts[k].y)) <= threshold;
      if (next[k]) inliers.push_back(pts[k]);
    }
    if (inliers.size() < 6) return fit;
    bool same = next == in;
    in.swap(next);
    if (annealed && same) break;
    if (!fit_outline(inliers, &current)) return fit;
    if (!annealed) {
      threshold = std::max(floor, 0.6 * threshold);
      annealed = threshold <= floor;
    }
    if (annealed) {
      std::vector<double> abs_res;
      abs_res.reserve(inliers.size());
      for (const EdgePoint &p : inliers)
        abs_res.push_back(std::fabs(ellipse_residual(current, p.x, p.y)));
      threshold = std::min(floor, std::max(0.5, 3.0 * 1.4826 * median(abs_res)));
    }
  }
  std::vector<double> strengths;
  double sum2 = 0;
  int bins = std::max(32, static_cast<int>(CF_PI * (current.a + current.b) / 2.0));
  std::vector<char> covered(static_cast<size_t>(bins), 0);
  inliers.clear();
  for (const EdgePoint &p : pts) {
    double res = ellipse_residual(current, p.x, p.y);
    if (std::fabs(res) > threshold) continue;
    inliers.push_back(p);
    strengths.push_back(p.strength);
    sum2 += res * res;
    covered[static_cast<size_t>(direction_bin(current, p.x, p.y, bins))] = 1;
  }
  if (inliers.size() < 6) return fit;
  fit.ok = plausible(current);
  fit.ellipse = current;
  fit.inliers = std::move(inliers);
  fit.rms = std::sqrt(sum2 / static_cast<double>(fit.inliers.size()));
  fit.median_strength = median(strengths);
  fit.coverage = static_cast<double>(std::count(covered.begin(), covered.end(), 1)) /
                 static_cast<double>(bins);
  fit.threshold = threshold;
  return fit;
}

// The fraction of the ellipse's direction bins with an edge point within
// `band` of it.
double coverage_of(const Renditions &r, const Ellipse &e, double band) {
  int bins = std::max(32, static_cast<int>(CF_PI * (e.a + e.b) / 2.0));
  std::vector<char> covered(static_cast<size_t>(bins), 0);
  for (const EdgePoint &p : collect(r, e, band))
    covered[static_cast<size_t>(direction_bin(e, p.x, p.y, bins))] = 1;
  return static_cast<double>(std::count(covered.begin(), covered.end(), 1)) /
         static_cast<double>(bins);
}

}  // namespace

Fit refine(const Renditions &r, const Ellipse &candidate, double wide) {
  double r0 = 0.5 * (candidate.a + candidate.b);
  double narrow0 = std::max(2.0, 0.02 * r0);
  Fit first = robust_fit(collect(r, candidate, wide), candidate, wide, narrow0);
  if (!first.ok) return first;
  double r1 = 0.5 * (first.ellipse.a + first.ellipse.b);
  double narrow = std::max(2.0, 0.02 * r1);
  Fit fit = robust_fit(collect(r, first.ellipse, narrow), first.ellipse, narrow, 0.5 * narrow);
  if (!fit.ok) return fit;
  double offset = 2 * narrow, sum = 0;
  int count = 0;
  for (double d : {offset, -offset}) {
    Ellipse moved = fit.ellipse;
    moved.a += d;
    moved.b += d;
    if (moved.b < 2) continue;
    sum += coverage_of(r, moved, fit.threshold);
    ++count;
  }
  int bins = std::max(32, static_cast<int>(CF_PI * (fit.ellipse.a + fit.ellipse.b) / 2.0));
  fit.chance = std::min(std::max(count ? sum / count : 0.0, 1.0 / bins), 0.95);
  fit.significance =
      (fit.coverage - fit.chance) * std::sqrt(bins / (fit.chance * (1 - fit.chance)));
  return fit;
}

}  // namespace cf_sphere_cv
