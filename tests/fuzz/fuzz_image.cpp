/* libFuzzer target for reading images (cf_image_read_header and
 * cf_image_read_sized: the dispatcher src/capture/image_io.c and the
 * codecs it picks from a file's first bytes, PNG, JPEG, OpenEXR and PFM;
 * built and run by scripts/fuzz.sh): the first byte picks the file's
 * extension (.png .exr .tif .jpg .hdr .pfm, by its value modulo 6), the
 * rest is the file. Other formats go to OpenImageIO's module, which the
 * fuzz build does not have: they are refused, naming the file. Images
 * that decode are checked for non-finite values and every pixel is
 * decoded to radiance (cf_decode_pixel) as the capture does.
 *
 * As the capture reads its photos: the header first (cf_image_read_header),
 * then the pixels of an image of that size (cf_image_read_sized). Small
 * size caps: a header whose image holds more than 2^22 values (16 MB of
 * floats) is not decoded here, so that libFuzzer's memory limit reports
 * real leaks and blow-ups, not large images (the capture compares the
 * header with its camera instead).
 * libpng, libjpeg and OpenEXR are Debian's builds, not instrumented:
 * crashes in them are found, but their coverage does not guide the
 * fuzzing; clayfit's codecs around them are instrumented.
 *
 * Every input is also parsed as a JPEG's markers (cf_jpeg_coding_parse, the
 * quality and chroma the fit's model of JPEG coding reads): a failure names
 * the input, a success gives a quality of 1 to 100.
 *
 * Besides crashes and sanitizer reports, a broken promise aborts: a failure
 * leaves the image empty and names the file; a success gives 1 to 4
 * channels of a positive size. */
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "clayfit/image.h"
#include "fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

namespace {

const char *const kExtensions[6] = {"png", "exr", "tif", "jpg", "hdr", "pfm"};
const int64_t kMaxValues = int64_t(1) << 22;

void decode_all(const cf_image *image) {
  static const cf_decode decodes[3] = {
      {CF_TRANSFER_LINEAR, 1.0, 0.0, INFINITY, 1.0},
      {CF_TRANSFER_SRGB, 1.0, 0.01, 1.0, 0.5},
      {CF_TRANSFER_GAMMA, 2.2, 0.0, 0.9, 2.0},
  };
  const size_t pixels = size_t(image->width) * size_t(image->height);
  for (const cf_decode &decode : decodes)
    for (size_t i = 0; i < pixels; ++i) {
      double radiance[3];
      unsigned clipped = cf_decode_pixel(&decode, image->pixels + i * size_t(image->channels),
                                         image->channels, radiance);
      fuzz_require(clipped <= 7u, "a clip mask of three bits", "");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) return 0;
  char name[16], path[4096];
  std::snprintf(name, sizeof name, "image.%s", kExtensions[data[0] % 6]);
  fuzz_write(name, data + 1, size - 1, path);
  cf_error err = {};
  cf_jpeg_coding coding;
  if (cf_jpeg_coding_parse(data + 1, size - 1, "input", &coding, &err) == CF_OK)
    fuzz_require(coding.quality >= 1 && coding.quality <= 100, "a quality of 1 to 100", "");
  else
    fuzz_require(std::strstr(err.message, "input") != nullptr, "a failure names the input",
                 err.message);
  err = {};
  cf_image_header header;
  cf_status s = cf_image_read_header(path, &header, &err);
  if (s != CF_OK) {
    fuzz_require(err.status == s && std::strstr(err.message, path),
                 "a failure of the header names the file", err.message);
    return 0;
  }
  fuzz_require(
      header.width > 0 && header.height > 0 && header.channels >= 1 && header.channels <= 4,
      "a header of a positive size and 1 to 4 channels", "");
  if (int64_t(header.width) * header.height * header.channels > kMaxValues) return 0;
  cf_image image = {0, 0, 0, nullptr};
  cf_image_info info;
  s = cf_image_read_sized(path, header.width, header.height, &image, &info, &err);
  if (s != CF_OK) {
    fuzz_require(err.status == s && image.pixels == nullptr && std::strstr(err.message, path),
                 "a failure leaves the image empty and names the file", err.message);
    return 0;
  }
  fuzz_require(image.width == header.width && image.height == header.height &&
                   image.channels == header.channels && image.pixels != nullptr,
               "the image the header declared", "");
  fuzz_require(std::memchr(info.format, '\0', sizeof info.format) != nullptr,
               "a terminated format name", "");
  cf_error finite = {};
  if (cf_image_check_finite(&image, path, &finite) != CF_OK)
    fuzz_require(std::strstr(finite.message, path) != nullptr, "non-finite values name the file",
                 finite.message);
  decode_all(&image);
  cf_image_free(&image);
  return 0;
}
