// The sphere's silhouette in one image: a thin adapter over OpenCV 4.6
// (src/capture/include/capture/sphere_silhouette.h). C linkage; no exception leaves it.
//
// Pixel convention. OpenCV puts the centre of pixel (col, row) at the
// integer point (col, row); COLMAP (and cf_image) at (col + 0.5, row + 0.5).
// Everything below works in OpenCV's coordinates and converts once, with
// kOpenCvToColmap, on the way in (the hint) and out (to_colmap(), the
// boundary points).
//
// With a mask: the largest outer contour (cv::findContours), filled; its
// boundary points are the midpoints of the pixel edges between it and the
// rest; cv::fitEllipse (Fitzgibbon, Pilu & Fisher 1996/1999) through them.
//
// Without a mask:
//  1. grey = mean of the first three channels, linear; scaled so that its
//     99.5th percentile is 1 (photos may be dim or bright).
//  2. Candidates: an 8-bit rendition of it (clamped, gamma 1/2.2 so that
//     dim parts keep some contrast, Gaussian blur) goes to Canny (1986)
//     and to cv::HoughCircles (HOUGH_GRADIENT, the 2-1 Hough transform of
//     Yuen et al. 1990), narrowed by the hint. Hough's votes favour large
//     circles in texture, so its circles are re-ranked by how much more of
//     each circle has radial edges near it than chance (below), and the
//     best 16 are refined; the hint's own circle is refined too.
//  3. Refinement: the Canny pixels near the candidate whose gradient is
//     within 30° of its normal, each moved to sub-pixel precision along
//     its gradient, to the maximum of the gradient magnitude of the
//     blurred *linear* grey (Devernay 1995; the blur of a lens acts on
//     linear radiance, so that is where the edge is); per direction from
//     the centre only the strongest are kept (clutter and texture give
//     weaker or fewer edges); then cv::fitEllipse (Kasa's circle, 1976,
//     if the ellipse comes out implausibly eccentric from a partial arc)
//     with iterative rejection of far points, the threshold shrinking
//     from the band's width to a few robust sigmas. Twice: a wide band
//     around the candidate, then a narrow one around the first fit.
//  4. Judgement ("a contrario", Desolneux, Moisan & Morel 2008): the
//     fraction of the outline's directions with edge points (coverage) is
//     compared with that of the same outline moved inward and outward
//     (what clutter alone gives there); the excess in binomial standard
//     deviations is the significance. Of the candidates that pass every
//     check (radius and centre in the range searched, coverage,
//     significance, RMS, edge strength), the one with the most directions
//     covered beyond chance is the sphere; if none passes, CF_ENOTFOUND
//     says why the best failed.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <new>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/vec.h"
#include "capture/sphere_silhouette.h"

namespace {

// OpenCV's pixel centres are at integers, COLMAP's at integer + 0.5.
constexpr double kOpenCvToColmap = 0.5;

constexpr double kSearchSigma = 1.5;       // px, blur of the 8-bit rendition
constexpr double kEdgeSigma = 1.0;         // px, blur of the linear grey
constexpr double kGamma = 1.0 / 2.2;       // 8-bit rendition for the search only
constexpr double kPercentile = 0.995;      // of grey, mapped to 1
constexpr int kMaxHoughSize = 1200;        // px: larger images are searched downscaled
constexpr size_t kMaxHoughCircles = 1000;  // ranked by their support
constexpr size_t kMaxCandidates = 16;      // Hough circles refined
constexpr double kMinCoverage = 0.35;      // of the outline's directions with edge points
constexpr double kMaxRmsOfBand = 0.35;     // RMS residual / narrow band half-width
constexpr double kMinEdgeContrast = 3.0;   // median boundary gradient / median image gradient
constexpr double kMinAxisRatio = 0.5;      // b / a of a plausible sphere outline
constexpr double kMinSignificance = 10.0;  // coverage above chance, binomial sigmas
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

struct Ellipse {                                   // OpenCV coordinates
  double cx = 0, cy = 0, a = 0, b = 0, angle = 0;  // a >= b, angle of a from +x toward +y
};

struct EdgePoint {
  double x, y;      // sub-pixel, OpenCV coordinates
  double strength;  // gradient magnitude of the linear grey
};

struct Fit {
  bool ok = false;
  Ellipse ellipse;
  std::vector<EdgePoint> inliers;
  double coverage = 0, rms = 0, median_strength = 0, band = 0;
  double threshold = 0;     // of the inliers' residuals, px
  double chance = 0;        // coverage of outlines offset inward and outward
  double significance = 0;  // (coverage − chance) in binomial standard deviations
};

// The images one detection works on.
struct Renditions {
  cv::Mat1f linear;              // grey / percentile, blurred
  cv::Mat1f gx, gy, mag;         // its gradient (per pixel)
  cv::Mat1b search;              // 8-bit, gamma, blurred
  cv::Mat1b edge_map;            // Canny of `search`
  std::vector<cv::Point> edges;  // its pixels
  double median_mag = 0;         // of `mag` over the image
};

const char *image_name(const char *name) {
  return name && *name ? name : "(unnamed image)";
}

cf_ellipse to_colmap(const Ellipse &e) {
  cf_ellipse out;
  out.cx = e.cx + kOpenCvToColmap;
  out.cy = e.cy + kOpenCvToColmap;
  out.a = e.a;
  out.b = e.b;
  out.angle = e.angle;
  return out;
}

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

Ellipse circle(double cx, double cy, double r) {
  return normalized(cx, cy, r, r, 0.0);
}

// cv::fitEllipse's RotatedRect: size.width is the full axis along `angle`
// (degrees, from +x toward +y), size.height the other one.
Ellipse from_rotated_rect(const cv::RotatedRect &box) {
  return normalized(box.center.x, box.center.y, 0.5 * box.size.width, 0.5 * box.size.height,
                    box.angle * CF_PI / 180.0);
}

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

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  return values[mid];
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

// ---- the mask ----

cf_status from_mask(const cf_image &mask, const char *name, Ellipse *out,
                    std::vector<EdgePoint> *points, cf_error *err) {
  cv::Mat1b binary(mask.height, mask.width);
  for (int y = 0; y < mask.height; ++y)
    for (int x = 0; x < mask.width; ++x) {
      float value = mask.pixels[(static_cast<size_t>(y) * static_cast<size_t>(mask.width) +
                                 static_cast<size_t>(x)) *
                                static_cast<size_t>(mask.channels)];
      binary(y, x) = std::isfinite(value) && value != 0.0f ? 255 : 0;
    }
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(binary, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  if (contours.empty())
    return cf_error_set(err, CF_ENOTFOUND, "%s: the sphere's mask is empty.", name);
  size_t best = 0;
  double best_area = -1;
  for (size_t k = 0; k < contours.size(); ++k) {
    double area = cv::contourArea(contours[k]);
    if (area > best_area) {
      best_area = area;
      best = k;
    }
  }
  // The component with its holes filled; its boundary is the pixel edges
  // between it and the rest, whose midpoints are (OpenCV coordinates)
  // (x ± 0.5, y) and (x, y ± 0.5).
  cv::Mat1b filled = cv::Mat1b::zeros(binary.size());
  cv::drawContours(filled, contours, static_cast<int>(best), cv::Scalar(255), cv::FILLED,
                   cv::LINE_8);
  cv::Rect box = cv::boundingRect(contours[best]);
  points->clear();
  auto inside = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < filled.cols && y < filled.rows && filled(y, x) != 0;
  };
  for (int y = box.y; y < box.y + box.height; ++y)
    for (int x = box.x; x < box.x + box.width; ++x) {
      if (!inside(x, y)) continue;
      if (!inside(x - 1, y)) points->push_back({x - 0.5, static_cast<double>(y), 1.0});
      if (!inside(x + 1, y)) points->push_back({x + 0.5, static_cast<double>(y), 1.0});
      if (!inside(x, y - 1)) points->push_back({static_cast<double>(x), y - 0.5, 1.0});
      if (!inside(x, y + 1)) points->push_back({static_cast<double>(x), y + 0.5, 1.0});
    }
  if (points->size() < 5 || best_area <= 0)
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: the largest region of the sphere's mask (%zu boundary points) is "
                        "too small to fit an ellipse.",
                        name, points->size());
  std::vector<cv::Point2f> pts;
  pts.reserve(points->size());
  for (const EdgePoint &p : *points)
    pts.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  Ellipse e = from_rotated_rect(cv::fitEllipse(pts));
  if (!(e.b > 0) || !std::isfinite(e.a) || !std::isfinite(e.cx) || !std::isfinite(e.cy))
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: no ellipse fits the boundary of the sphere's mask (%zu points).", name,
                        points->size());
  *out = e;
  return CF_OK;
}

// ---- the image ----

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

// Renditions of the image; false if it is black.
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

// Canny's high threshold for the 8-bit rendition: from its strongest
// gradients, so that it follows the image's contrast, and well above its
// typical gradient, so that noise and fine texture do not make edges
// everywhere (which would also make the Hough transform slow).
double canny_high(const cv::Mat1b &search) {
  cv::Mat1f dx, dy, mag;
  cv::Sobel(search, dx, CV_32F, 1, 0, 3);
  cv::Sobel(search, dy, CV_32F, 0, 1, 3);
  cv::magnitude(dx, dy, mag);
  double high = std::max(0.4 * quantile(mag, 0.99), 4.0 * quantile(mag, 0.5));
  return std::min(std::max(high, 12.0), 600.0);
}

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

// Two passes: a band of half-width `wide` around the candidate, then a
// narrow one (max(2, r/50) px) around the first fit. Then how much better
// than chance the outline is covered: chance is the coverage, within the
// same threshold, of the outline moved 2 narrow bands outward and inward
// (what clutter or texture alone gives there), and the significance is
// the excess in binomial standard deviations (an "a contrario" test,
// Desolneux, Moisan & Morel 2008).
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

struct SearchRange {
  double min_radius, max_radius;
  bool has_centre;
  double cx, cy, max_offset;  // OpenCV coordinates
};

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

// Whether a refined outline is plausibly the sphere; CF_ENOTFOUND says why not.
cf_status judge(const Fit &fit, const SearchRange &range, double median_mag, const char *name,
                cf_error *err) {
  cf_ellipse found = to_colmap(fit.ellipse);
  double radius = 0.5 * (fit.ellipse.a + fit.ellipse.b);
  if (radius < 0.9 * range.min_radius || radius > 1.1 * range.max_radius)
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: the best circle (centre %.1f, %.1f) has radius %.1f px, outside the "
                        "range searched (%.1f to %.1f px), so it is not taken for the sphere.",
                        name, found.cx, found.cy, radius, range.min_radius, range.max_radius);
  if (range.has_centre &&
      std::hypot(fit.ellipse.cx - range.cx, fit.ellipse.cy - range.cy) > range.max_offset)
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: the best circle (centre %.1f, %.1f, radius %.1f px) is more than "
                        "%.1f px from the expected centre (%.1f, %.1f), so it is not taken for "
                        "the sphere.",
                        name, found.cx, found.cy, radius, range.max_offset,
                        range.cx + kOpenCvToColmap, range.cy + kOpenCvToColmap);
  if (fit.coverage < kMinCoverage)
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: the best circle (centre %.1f, %.1f, radius %.1f px) has edge points "
                        "on only %.0f%% of its outline (at least %.0f%% needed), so it is not "
                        "taken for the sphere.",
                        name, found.cx, found.cy, radius, 100 * fit.coverage, 100 * kMinCoverage);
  if (fit.significance < kMinSignificance)
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: the best circle (centre %.1f, %.1f, radius %.1f px) has edge points "
                        "on %.0f%% of its outline, but outlines a few px inside and outside it "
                        "have them on %.0f%% (%.1f standard deviations apart, at least %.0f "
                        "needed), so it is not taken for the sphere.",
                        name, found.cx, found.cy, radius, 100 * fit.coverage, 100 * fit.chance,
                        fit.significance, kMinSignificance);
  if (fit.rms > kMaxRmsOfBand * fit.band)
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: the best circle (centre %.1f, %.1f, radius %.1f px) fits its edge "
                        "points with an RMS of %.2f px (at most %.2f allowed), so it is not taken "
                        "for the sphere.",
                        name, found.cx, found.cy, radius, fit.rms, kMaxRmsOfBand * fit.band);
  if (fit.median_strength < kMinEdgeContrast * median_mag)
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: the best circle (centre %.1f, %.1f, radius %.1f px) has edges only "
                        "%.1f times as strong as the image's typical gradient (at least %.0f "
                        "needed), so it is not taken for the sphere.",
                        name, found.cx, found.cy, radius, fit.median_strength / median_mag,
                        kMinEdgeContrast);
  return CF_OK;
}

cf_status from_image(const cf_image &image, const cf_silhouette_hint *hint, const char *name,
                     Ellipse *out, std::vector<EdgePoint> *points, cf_error *err) {
  if (image.width < 8 || image.height < 8)
    return cf_error_set(err, CF_ENOTFOUND, "%s: the image (%d × %d) is too small to hold a sphere.",
                        name, image.width, image.height);
  Renditions r;
  if (!make_renditions(image, &r))
    return cf_error_set(err, CF_ENOTFOUND, "%s: the image is black, so it shows no sphere.", name);
  double canny = canny_high(r.search);
  cv::Canny(r.search, r.edge_map, 0.5 * canny, canny, 3, true);
  cv::findNonZero(r.edge_map, r.edges);

  SearchRange range{};
  double min_side = std::min(image.width, image.height);
  bool hinted = hint && hint->radius > 0 && std::isfinite(hint->radius) &&
                std::isfinite(hint->center[0]) && std::isfinite(hint->center[1]);
  if (hinted) {
    range.min_radius = 0.7 * hint->radius;
    range.max_radius = 1.4 * hint->radius;
    range.has_centre = true;
    range.cx = hint->center[0] - kOpenCvToColmap;
    range.cy = hint->center[1] - kOpenCvToColmap;
    range.max_offset = 0.6 * hint->radius;
  } else {
    range.min_radius = std::max(4.0, min_side / 50.0);
    range.max_radius = min_side / 2.0;
    range.has_centre = false;
  }
  std::vector<Ellipse> candidates = hough_candidates(r, range, canny);
  size_t num_hough = candidates.size();
  if (hinted) candidates.push_back(circle(range.cx, range.cy, hint->radius));
  if (candidates.empty())
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: no circle of radius %.0f to %.0f px stands out among the image's "
                        "edges, so no sphere was found.",
                        name, range.min_radius, range.max_radius);

  // Each candidate refined and judged; the best of those that pass, else
  // the reason the best of all failed.
  Fit best;
  double best_score = -std::numeric_limits<double>::infinity();
  double best_failed_score = best_score;
  cf_error reason = {CF_OK, {0}};
  for (size_t k = 0; k < candidates.size(); ++k) {
    const Ellipse &candidate = candidates[k];
    // Hough's circles are within a few px (they have edges near them);
    // the hint's may be off by a third of its radius
    double wide = k < num_hough ? std::max(4.0, 0.1 * candidate.a) : 0.35 * candidate.a;
    Fit fit = refine(r, candidate, wide);
    if (!fit.ok) continue;
    // the number of the outline's directions with edge points beyond
    // chance: the longest clean outline wins (the significance only tells
    // whether it is there at all; it saturates where clutter is rare)
    int bins = std::max(32, static_cast<int>(CF_PI * (fit.ellipse.a + fit.ellipse.b) / 2.0));
    double score = (fit.coverage - fit.chance) * bins;
    cf_error why = {CF_OK, {0}};
    if (judge(fit, range, r.median_mag, name, &why) == CF_OK) {
      if (score > best_score) {
        best_score = score;
        best = std::move(fit);
      }
    } else if (score > best_failed_score) {
      best_failed_score = score;
      reason = why;
    }
  }
  if (!best.ok) {
    if (reason.status != CF_OK) {
      if (err) *err = reason;
      return reason.status;
    }
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: none of the %zu candidate circles has an outline of edge points "
                        "that an ellipse fits, so no sphere was found.",
                        name, candidates.size());
  }
  *out = best.ellipse;
  *points = std::move(best.inliers);
  return CF_OK;
}

cf_status check_image(const cf_image *image, const char *what, const char *name, cf_error *err) {
  if (!image->pixels || image->width <= 0 || image->height <= 0 || image->channels < 1 ||
      image->channels > 4)
    return cf_error_set(err, CF_EINVAL,
                        "%s: the %s (%d × %d, %d channels) is empty or has an unsupported number "
                        "of channels.",
                        name, what, image->width, image->height, image->channels);
  return CF_OK;
}

cf_status detect(const cf_image *image, const cf_silhouette_hint *hint, const char *name,
                 cf_ellipse *ellipse, double *boundary, size_t max_points, size_t *num_points,
                 cf_error *err) {
  const cf_image *mask = hint ? hint->mask : nullptr;
  if (!ellipse || (!boundary && max_points > 0))
    return cf_error_set(err, CF_EINVAL, "%s: the sphere detection needs somewhere to write.", name);
  if (!image && !mask)
    return cf_error_set(err, CF_EINVAL, "%s: the sphere detection needs an image or a mask.", name);
  cf_status status;
  if (image && (status = check_image(image, "image", name, err)) != CF_OK) return status;
  if (mask && (status = check_image(mask, "mask", name, err)) != CF_OK) return status;
  if (image && mask && (image->width != mask->width || image->height != mask->height))
    return cf_error_set(err, CF_EINVAL, "%s: the mask is %d × %d but the image is %d × %d.", name,
                        mask->width, mask->height, image->width, image->height);

  Ellipse found;
  std::vector<EdgePoint> points;
  status = mask ? from_mask(*mask, name, &found, &points, err)
                : from_image(*image, hint, name, &found, &points, err);
  if (status != CF_OK) return status;

  // along the outline, so that an evenly spaced subset spreads around it
  std::vector<std::pair<double, size_t>> order(points.size());
  for (size_t k = 0; k < points.size(); ++k)
    order[k] = {std::atan2(points[k].y - found.cy, points[k].x - found.cx), k};
  std::sort(order.begin(), order.end());

  *ellipse = to_colmap(found);
  size_t count = std::min(max_points, points.size());
  for (size_t k = 0; k < count; ++k) {
    // evenly spaced when there are more points than room
    size_t src = points.size() > max_points ? k * points.size() / max_points : k;
    const EdgePoint &p = points[order[src].second];
    boundary[2 * k] = p.x + kOpenCvToColmap;
    boundary[2 * k + 1] = p.y + kOpenCvToColmap;
  }
  if (num_points) *num_points = count;
  return CF_OK;
}

}  // namespace

extern "C" cf_status cf_detect_sphere_silhouette(const cf_image *image,
                                                 const cf_silhouette_hint *hint, const char *name,
                                                 cf_ellipse *ellipse, double *boundary,
                                                 size_t max_points, size_t *num_points,
                                                 cf_error *err) {
  const char *label = image_name(name);
  if (num_points) *num_points = 0;
  try {
    return detect(image, hint, label, ellipse, boundary, max_points, num_points, err);
  } catch (const cv::Exception &e) {
    return cf_error_set(err, CF_ENUMERIC, "%s: OpenCV failed while looking for the sphere: %s",
                        label, e.what());
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while looking for the sphere.", label);
  } catch (const std::exception &e) {
    return cf_error_set(err, CF_ENUMERIC, "%s: the sphere detection failed: %s", label, e.what());
  } catch (...) {
    return cf_error_set(err, CF_ENUMERIC, "%s: the sphere detection failed.", label);
  }
}
