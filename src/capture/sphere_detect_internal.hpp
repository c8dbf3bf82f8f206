// Private to the sphere's detection (the overview is at the top of
// sphere_detect.cpp): its types, in OpenCV's pixel coordinates, and the
// steps that sphere_edges.cpp (renditions, refinement, outline geometry)
// and sphere_hough.cpp (candidate circles) give the other files. C++ only.
#ifndef CLAYFIT_SPHERE_DETECT_INTERNAL_HPP
#define CLAYFIT_SPHERE_DETECT_INTERNAL_HPP

#include <vector>

#include <opencv2/core.hpp>

#include "clayfit/image.h"

namespace cf_sphere_cv {

constexpr double kSearchSigma = 1.5;  // px, blur of the 8-bit rendition

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

// The radii searched and, with a hint, the centre and how far from it.
struct SearchRange {
  double min_radius, max_radius;
  bool has_centre;
  double cx, cy, max_offset;  // OpenCV coordinates
};

// ---- sphere_edges.cpp ----

// A circle as an Ellipse.
Ellipse circle(double cx, double cy, double r);

// cv::fitEllipse's RotatedRect: size.width is the full axis along `angle`
// (degrees, from +x toward +y), size.height the other one.
Ellipse from_rotated_rect(const cv::RotatedRect &box);

// The median (0 if there are no values).
double median(std::vector<double> values);

// Renditions of the image; false if it is black.
bool make_renditions(const cf_image &image, Renditions *r);

// Canny's high threshold for the 8-bit rendition: from its strongest
// gradients, so that it follows the image's contrast, and well above its
// typical gradient, so that noise and fine texture do not make edges
// everywhere (which would also make the Hough transform slow).
double canny_high(const cv::Mat1b &search);

// Two passes: a band of half-width `wide` around the candidate, then a
// narrow one (max(2, r/50) px) around the first fit. Then how much better
// than chance the outline is covered: chance is the coverage, within the
// same threshold, of the outline moved 2 narrow bands outward and inward
// (what clutter or texture alone gives there), and the significance is
// the excess in binomial standard deviations (an "a contrario" test,
// Desolneux, Moisan & Morel 2008).
Fit refine(const Renditions &r, const Ellipse &candidate, double wide);

// ---- sphere_hough.cpp ----

// Hough's circles in the range searched (and near the hint's centre), best
// first, near duplicates dropped, at most kMaxCandidates.
std::vector<Ellipse> hough_candidates(const Renditions &r, const SearchRange &range, double canny);

}  // namespace cf_sphere_cv

#endif
