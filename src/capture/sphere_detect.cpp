// The sphere's silhouette in one image: a thin adapter over OpenCV 4.6
// (src/capture/include/capture/sphere_silhouette.h). C linkage; no exception leaves it.
//
// Pixel convention. OpenCV puts the centre of pixel (col, row) at the
// integer point (col, row); COLMAP (and cf_image) at (col + 0.5, row + 0.5).
// The detection works in OpenCV's coordinates and converts once, with
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
//
// The files: this one holds the mask, the judgement (4) and the entry
// point; sphere_edges.cpp steps 1 and 3 and the outline geometry;
// sphere_hough.cpp step 2; sphere_detect_internal.hpp what they share.
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

#include "sphere_detect_internal.hpp"

namespace cf_sphere_cv {

namespace {

// OpenCV's pixel centres are at integers, COLMAP's at integer + 0.5.
constexpr double kOpenCvToColmap = 0.5;

constexpr double kMinCoverage = 0.35;      // of the outline's directions with edge points
constexpr double kMaxRmsOfBand = 0.35;     // RMS residual / narrow band half-width
constexpr double kMinEdgeContrast = 3.0;   // median boundary gradient / median image gradient
constexpr double kMinSignificance = 10.0;  // coverage above chance, binomial sigmas

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

}  // namespace cf_sphere_cv

extern "C" cf_status cf_detect_sphere_silhouette(const cf_image *image,
                                                 const cf_silhouette_hint *hint, const char *name,
                                                 cf_ellipse *ellipse, double *boundary,
                                                 size_t max_points, size_t *num_points,
                                                 cf_error *err) {
  const char *label = cf_sphere_cv::image_name(name);
  if (num_points) *num_points = 0;
  try {
    return cf_sphere_cv::detect(image, hint, label, ellipse, boundary, max_points, num_points, err);
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
