/* The general image reader and writer (image_codec.h): a thin C++ layer
 * over OpenImageIO 2.4 with C linkage, for every format clayfit's own
 * codecs do not read (TIFF, Radiance HDR, and whatever else OpenImageIO
 * opens), and the reference the codecs' tests hold them to. Nothing
 * thrown by OpenImageIO or the standard library crosses the C boundary:
 * every entry point catches all and turns it into a cf_error naming the
 * file.
 *
 * Pixels are read with ImageInput::read_image(0, 0, 0, nchannels,
 * TypeDesc::FLOAT, ...), which scales integer samples to [0, 1] and applies
 * no colour transform ("oiio:ColorSpace" is metadata only; ImageInput never
 * linearises). "oiio:UnassociatedAlpha" = 1 keeps PNG and TIFF readers
 * from premultiplying colour by alpha and writers from dividing by it. */
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>

#include "image_codec.h"

namespace {

/* OpenImageIO's messages may span lines; keep ours on one. */
std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ' || text.back() == '.'))
    text.pop_back();
  for (char &c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text.empty() ? std::string("no details from OpenImageIO") : text;
}

/* Clear OpenImageIO's pending global error (it complains at exit about
 * messages never retrieved). */
void drain_errors() noexcept {
  try {
    OIIO::geterror();
  } catch (...) {
  }
}

/* A numeric attribute, or NaN when absent, non-numeric or not positive
 * (EXIF uses 0 for "unknown"). */
double positive_attribute(const OIIO::ImageSpec &spec, const char *name) {
  if (spec.getattributetype(name) == OIIO::TypeUnknown) return NAN;
  double value = spec.get_float_attribute(name, NAN);
  return std::isfinite(value) && value > 0.0 ? value : NAN;
}

bool is_float(const OIIO::TypeDesc &type) {
  return type.basetype == OIIO::TypeDesc::HALF || type.basetype == OIIO::TypeDesc::FLOAT ||
         type.basetype == OIIO::TypeDesc::DOUBLE;
}

void info_fill(cf_image_info *info, const OIIO::ImageInput &input, const OIIO::ImageSpec &spec) {
  if (!info) return;
  std::snprintf(info->format, sizeof info->format, "%s", input.format_name());
  info->is_float = is_float(spec.format);
  for (const OIIO::TypeDesc &channel : spec.channelformats) /* per-channel formats */
    info->is_float |= is_float(channel);
  info->bits_per_sample = int(spec.format.basesize() * 8);
  info->exposure_time = positive_attribute(spec, "ExposureTime");
  info->f_number = positive_attribute(spec, "FNumber");
  info->iso = positive_attribute(spec, "Exif:PhotographicSensitivity");
  if (std::isnan(info->iso)) info->iso = positive_attribute(spec, "Exif:ISOSpeedRatings");
}

/* Integer samples scaled to [0, 1] as OpenImageIO's conversion to FLOAT
 * does (image_scale_u8/_u16, bit for bit): OpenImageIO's own took a
 * seventh of loading DiLiGenT's 96 16-bit PNGs. */
template <typename T>
bool read_scaled(OIIO::ImageInput &input, const OIIO::ImageSpec &spec, OIIO::TypeDesc type,
                 float *pixels) {
  const size_t values = size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels);
  std::unique_ptr<T[]> stored(new T[values]); /* not zeroed: read over */
  if (!input.read_image(0, 0, 0, spec.nchannels, type, stored.get())) return false;
  if (sizeof(T) == 1)
    image_scale_u8(reinterpret_cast<const uint8_t *>(stored.get()), values, pixels);
  else
    image_scale_u16(reinterpret_cast<const uint16_t *>(stored.get()), values, pixels);
  return true;
}

/* Every sample as float, integer ones scaled to [0, 1]. */
bool read_pixels(OIIO::ImageInput &input, const OIIO::ImageSpec &spec, float *pixels) {
  if (spec.channelformats.empty() && spec.format == OIIO::TypeDesc::UINT16)
    return read_scaled<uint16_t>(input, spec, OIIO::TypeDesc::UINT16, pixels);
  if (spec.channelformats.empty() && spec.format == OIIO::TypeDesc::UINT8)
    return read_scaled<uint8_t>(input, spec, OIIO::TypeDesc::UINT8, pixels);
  return input.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels);
}

/* The file opened and its header checked: one 2D, flat image
 * (image_header_accept), whole (data window = display window). */
cf_status open_checked(const char *path, int width, int height,
                       std::unique_ptr<OIIO::ImageInput> &input, cf_error *err) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  input = OIIO::ImageInput::open(path, &config);
  if (!input)
    return cf_error_set(err, CF_EIO, "%s: cannot read this image: %s", path,
                        one_line(OIIO::geterror()).c_str());
  const OIIO::ImageSpec &spec = input->spec();
  if (spec.deep)
    return cf_error_set(err, CF_EUNSUPPORTED, "%s: deep images are not supported", path);
  if (spec.depth > 1)
    return cf_error_set(err, CF_EUNSUPPORTED, "%s: a volume image (depth %d) is not supported",
                        path, spec.depth);
  cf_status s = image_header_accept(path, spec.width, spec.height, spec.nchannels, width, height,
                                    err);
  if (s != CF_OK) return s;
  if (spec.depth != 1)
    return cf_error_set(err, CF_EPARSE, "%s: zero size (depth %d)", path, spec.depth);
  if (spec.x != spec.full_x || spec.y != spec.full_y || spec.width != spec.full_width ||
      spec.height != spec.full_height)
    return image_window_refuse(path, spec.width, spec.height, spec.x, spec.y, spec.full_width,
                               spec.full_height, spec.full_x, spec.full_y, err);
  return CF_OK;
}

/* image_oiio_read's body. */
cf_status read_image(const char *path, int width, int height, cf_image_header *header,
                     cf_image *image, cf_error *err) {
  std::unique_ptr<OIIO::ImageInput> input;
  cf_status status = open_checked(path, width, height, input, err);
  if (status != CF_OK) return status;
  const OIIO::ImageSpec &spec = input->spec();
  header->width = spec.width;
  header->height = spec.height;
  header->channels = spec.nchannels;
  info_fill(&header->info, *input, spec);
  if (image) {
    status = cf_image_alloc(image, spec.width, spec.height, spec.nchannels, err);
    if (status != CF_OK) {
      cf_error_prefix(err, "%s", path);
      return status;
    }
    if (!read_pixels(*input, spec, image->pixels)) {
      cf_image_free(image);
      return cf_error_set(err, CF_EIO, "%s: cannot read the pixels: %s", path,
                          one_line(input->geterror()).c_str());
    }
  }
  input->close();
  input->geterror(); /* nothing left pending */
  return CF_OK;
}

/* What went wrong reading path, from an exception: out of memory is not
 * a bad input. */
cf_status read_failed(const char *path, cf_image *image, cf_error *err) {
  if (image) cf_image_free(image);
  drain_errors();
  try {
    throw;
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while decoding it", path);
  } catch (const std::exception &e) {
    return cf_error_set(err, CF_EIO, "%s: reading failed: %s", path, e.what());
  } catch (...) {
    return cf_error_set(err, CF_EIO, "%s: reading failed (an unknown exception)", path);
  }
}

/* ---- writing ---- */

/* The sample type of `bits` in the format of `path`'s extension (the
 * dispatcher checked that the format takes them). */
OIIO::TypeDesc sample_type(const std::string &format, int bits) {
  if (format == "openexr") return bits == 16 ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
  if (bits == 8) return OIIO::TypeDesc::UINT8;
  if (bits == 16) return OIIO::TypeDesc::UINT16;
  return OIIO::TypeDesc::FLOAT;
}

/* OpenImageIO's name of a chroma subsampling. */
const char *subsampling_name(cf_chroma chroma) {
  return chroma == CF_CHROMA_420 ? "4:2:0" : chroma == CF_CHROMA_422 ? "4:2:2" : "4:4:4";
}

cf_status write_image(const char *path, const cf_image *image, int bits, const cf_image_info *info,
                      int quality, cf_chroma chroma, cf_error *err) {
  auto output = OIIO::ImageOutput::create(path);
  if (!output)
    return cf_error_set(err, CF_EUNSUPPORTED, "%s: OpenImageIO has no writer for it: %s", path,
                        one_line(OIIO::geterror()).c_str());
  const std::string format = output->format_name();
  OIIO::ImageSpec spec(image->width, image->height, image->channels, sample_type(format, bits));
  spec.attribute("oiio:UnassociatedAlpha", 1);
  if (format == "openexr" || format == "tiff") spec.attribute("compression", "zip");
  if (format == "jpeg") {
    spec.attribute("Compression", "jpeg:" + std::to_string(quality));
    spec.attribute("jpeg:subsampling", subsampling_name(chroma));
  }
  if (info) {
    if (std::isfinite(info->exposure_time))
      spec.attribute("ExposureTime", float(info->exposure_time));
    if (std::isfinite(info->f_number)) spec.attribute("FNumber", float(info->f_number));
    if (std::isfinite(info->iso))
      spec.attribute("Exif:PhotographicSensitivity", int(std::lround(info->iso)));
  }
  if (!output->open(path, spec))
    return cf_error_set(err, CF_EIO, "%s: cannot create the file: %s", path,
                        one_line(output->geterror()).c_str());
  bool ok = output->write_image(OIIO::TypeDesc::FLOAT, image->pixels);
  ok = output->close() && ok;
  std::string failed = output->geterror(); /* the PNG writer reports a failed write
                                              (/dev/full, a full disk) only here; the
                                              TIFF writer leaves a harmless note on
                                              its EXIF directory there */
  if (!ok || (format == "png" && !failed.empty()))
    return cf_error_set(err, CF_EIO, "%s: could not write the image: %s", path,
                        one_line(failed).c_str());
  return CF_OK;
}

/* cf_image_jpeg_roundtrip's body: code `in` into memory, decode it back. */
cf_status jpeg_roundtrip(const cf_image *in, int quality, const char *subsampling, cf_image *out,
                         cf_error *err) {
  OIIO::Filesystem::IOVecOutput coded;
  auto output = OIIO::ImageOutput::create("jpeg");
  if (!output)
    return cf_error_set(err, CF_EUNSUPPORTED, "OpenImageIO has no JPEG writer: %s",
                        one_line(OIIO::geterror()).c_str());
  OIIO::ImageSpec spec(in->width, in->height, in->channels, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:" + std::to_string(quality));
  spec.attribute("jpeg:subsampling", subsampling);
  bool ok = output->set_ioproxy(&coded) && output->open("coded.jpg", spec);
  ok = ok && output->write_image(OIIO::TypeDesc::FLOAT, in->pixels);
  ok = output->close() && ok;
  if (!ok)
    return cf_error_set(err, CF_EIO, "coding a JPEG in memory failed: %s",
                        one_line(output->geterror()).c_str());
  OIIO::Filesystem::IOMemReader reader(coded.buffer().data(), coded.buffer().size());
  auto input = OIIO::ImageInput::open("coded.jpg", nullptr, &reader);
  if (!input)
    return cf_error_set(err, CF_EIO, "decoding a JPEG from memory failed: %s",
                        one_line(OIIO::geterror()).c_str());
  cf_status s = cf_image_alloc(out, in->width, in->height, in->channels, err);
  if (s == CF_OK && !input->read_image(0, 0, 0, in->channels, OIIO::TypeDesc::FLOAT, out->pixels)) {
    cf_image_free(out);
    s = cf_error_set(err, CF_EIO, "decoding a JPEG from memory failed: %s",
                     one_line(input->geterror()).c_str());
  }
  input->close();
  return s;
}

}  // namespace

/* The module's entry points (image_io.c finds them with dlsym); every
 * other symbol of the module is hidden. */
#define EXPORTED __attribute__((visibility("default")))

extern "C" {

EXPORTED cf_status image_oiio_read(const char *path, int width, int height, cf_image_header *header,
                          cf_image *image, cf_error *err) {
  try {
    return read_image(path, width, height, header, image, err);
  } catch (...) {
    return read_failed(path, image, err);
  }
}

EXPORTED cf_status image_oiio_write(const char *path, const cf_image *image, int bits,
                           const cf_image_info *info, int quality, cf_chroma chroma,
                           cf_error *err) {
  try {
    return write_image(path, image, bits, info, quality, chroma, err);
  } catch (const std::exception &e) {
    drain_errors();
    return cf_error_set(err, CF_EIO, "%s: writing failed: %s", path, e.what());
  } catch (...) {
    return cf_error_set(err, CF_EIO, "%s: writing failed (an unknown exception)", path);
  }
}

EXPORTED cf_status image_oiio_jpeg_roundtrip(const cf_image *in, int quality, cf_chroma chroma,
                                    cf_image *out, cf_error *err) {
  try {
    return jpeg_roundtrip(in, quality, subsampling_name(chroma), out, err);
  } catch (const std::exception &e) {
    drain_errors();
    cf_image_free(out);
    return cf_error_set(err, CF_EIO, "a JPEG round trip failed: %s", e.what());
  } catch (...) {
    cf_image_free(out);
    return cf_error_set(err, CF_EIO, "a JPEG round trip failed (an unknown exception)");
  }
}

}  // extern "C"
