// Test-only helper: read a PNG with OpenCV's imgcodecs into a cf_image
// (cf_image_read is not used here so that this test depends on the sphere
// component only). The library itself reads images with OpenImageIO.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "clayfit/image.h"

extern "C" int sphere_test_read_png(const char *path, cf_image *out, char *why, size_t why_size);

// Values scaled to [0, 1] (value / (2^bits − 1)), channels in RGB order,
// top row first. Returns 0 and says why on failure. Free out->pixels.
extern "C" int sphere_test_read_png(const char *path, cf_image *out, char *why, size_t why_size) {
  try {
    cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
    if (m.empty()) {
      std::snprintf(why, why_size, "%s: OpenCV could not read it", path);
      return 0;
    }
    double scale = m.depth() == CV_16U ? 1.0 / 65535.0 : m.depth() == CV_8U ? 1.0 / 255.0 : 1.0;
    int channels = m.channels();
    if (channels == 3) cv::cvtColor(m, m, cv::COLOR_BGR2RGB);
    if (channels == 4) cv::cvtColor(m, m, cv::COLOR_BGRA2RGBA);
    cv::Mat f;
    m.convertTo(f, CV_32F, scale);
    size_t count = f.total() * static_cast<size_t>(channels);
    float *pixels = static_cast<float *>(std::malloc(count * sizeof(float)));
    if (!pixels) {
      std::snprintf(why, why_size, "%s: out of memory", path);
      return 0;
    }
    for (int y = 0; y < f.rows; ++y)
      std::memcpy(pixels + static_cast<size_t>(y) * f.cols * channels, f.ptr<float>(y),
                  static_cast<size_t>(f.cols) * channels * sizeof(float));
    out->width = f.cols;
    out->height = f.rows;
    out->channels = channels;
    out->pixels = pixels;
    return 1;
  } catch (const std::exception &e) {
    std::snprintf(why, why_size, "%s: %s", path, e.what());
    return 0;
  }
}
