/* The OpenEXR reader and writer (image_codec.h): a thin C++ layer over
 * OpenEXR 3.1's C++ API with C linkage. Nothing thrown crosses the C
 * boundary: out of memory is CF_ENOMEM, an OpenEXR exception a cf_error
 * naming the file (CF_EPARSE while the header is read, CF_EIO after).
 *
 * The reader returns bit for bit what OpenImageIO 2.4's OpenEXR reader
 * (src/openexr.imageio/exrinput.cpp, through image_oiio_read) returns: the
 * first part of a multi-part file (MultiPartInputFile and InputPart, as
 * there), scan lines or tiles (level 0 of a MIP map), its channel order,
 * HALF and FLOAT as float (exact), UINT scaled by 1 / (2^32 - 1) in float,
 * and the exposure time, f-number and ISO as OpenImageIO's metadata gives
 * them. The C++ API rather than OpenEXRCore (openexr.h): it is what
 * OpenImageIO 2.4 reads with (so a damaged file fails or passes alike), and
 * it decodes scan lines, tiles and every compression in one readPixels
 * call where the core library needs a loop over chunks per layout.
 *
 * Threads: MultiPartInputFile and OutputFile are given 0 (their default,
 * globalThreadCount(), is process-wide state that OpenImageIO sets; the
 * argument only sizes their buffers, the work runs on OpenEXR's global
 * pool, which clayfit leaves alone). With 0, the 4 HDRIs of
 * ../shared/data/hdri (512 x 256 half RGB) read in 19-31 ms against
 * image_oiio_read's 46-117 ms, and 2 measured no faster (test_image_exr
 * prints both readers' times; 3 runs each on a loaded 2-core machine). */
#include <OpenEXR/IexBaseExc.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfOutputFile.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "image_codec.h"

namespace {

/* No thread pool (see the top of the file). */
const int kThreads = 0;

/* ---- streams over a FILE ---- */

/* OpenEXR reading `file` (owned by the caller). */
class FileIn : public Imf::IStream {
 public:
  FileIn(const char *path, FILE *file) : Imf::IStream(path), file_(file) {}
  bool read(char c[], int n) override {
    if (n < 0 || std::fread(c, 1, size_t(n), file_) != size_t(n))
      throw Iex::InputExc("unexpected end of file");
    return true;
  }
  uint64_t tellg() override {
    const off_t at = ftello(file_);
    if (at < 0) throw Iex::IoExc("cannot tell the position in the file");
    return uint64_t(at);
  }
  void seekg(uint64_t pos) override {
    if (pos > uint64_t(INT64_MAX) || fseeko(file_, off_t(pos), SEEK_SET) != 0)
      throw Iex::InputExc("a seek in the file failed");
  }
  void clear() override {
    std::clearerr(file_);
  }

 private:
  FILE *file_;
};

/* OpenEXR writing `file`; a failed write is kept (`failed`) as well as
 * thrown, since OutputFile's destructor swallows what its last writes
 * throw (the offset table). */
class FileOut : public Imf::OStream {
 public:
  FileOut(const char *path, FILE *file) : Imf::OStream(path), file_(file) {}
  void write(const char c[], int n) override {
    if (n < 0 || std::fwrite(c, 1, size_t(n), file_) != size_t(n)) fail("a write failed");
  }
  uint64_t tellp() override { /* never throws: OutputFile's destructor calls it */
    const off_t at = ftello(file_);
    if (at < 0) failed = errno ? errno : EIO;
    return at < 0 ? 0 : uint64_t(at);
  }
  void seekp(uint64_t pos) override {
    if (pos > uint64_t(INT64_MAX) || fseeko(file_, off_t(pos), SEEK_SET) != 0)
      fail("a seek failed");
  }
  int failed = 0;

 private:
  [[noreturn]] void fail(const char *what) {
    failed = errno ? errno : EIO;
    throw Iex::IoExc(what);
  }
  FILE *file_;
};

/* An attribute's value as OpenEXR stores it (little-endian bytes). */
class Bytes : public Imf::OStream {
 public:
  Bytes() : Imf::OStream("attribute") {}
  void write(const char c[], int n) override {
    bytes.append(c, size_t(n));
  }
  uint64_t tellp() override {
    return bytes.size();
  }
  void seekp(uint64_t pos) override {
    bytes.resize(size_t(pos));
  }
  std::string bytes;
};

/* ---- channels in OpenImageIO's order ---- */

/* A channel's name split at its last dot: layer ("diffuse.", or "") and
 * suffix ("R"). */
struct Channel {
  std::string name, layer, suffix;
  int special;
  Imf::PixelType type;
  int x_sampling, y_sampling;
};

bool same_letters(const std::string &a, const char *b) { /* Strutil::iequals, ASCII */
  if (a.size() != std::strlen(b)) return false;
  for (size_t k = 0; k < a.size(); ++k)
    if (std::tolower((unsigned char)a[k]) != std::tolower((unsigned char)b[k])) return false;
  return true;
}

/* A suffix's rank within its layer: exrinput.cpp's ChanNameHolder::
 * compute_special_index, and compute_special_index_xyz for a layer holding
 * X and Y or Z (a position or a normal); 10000 for any other name. */
int special_index(const std::string &suffix, bool xyz) {
  static const char *const plain[] = {"R",    "Red",  "G",  "Green", "B",     "Blue", "Y",
                                      "real", "imag", "A",  "Alpha", "AR",    "RA",   "AG",
                                      "GA",   "AB",   "BA", "Z",     "Depth", "Zback"};
  static const char *const spatial[] = {"R",  "Red", "G",    "Green", "B",  "Blue",  "X",
                                        "Y",  "Z",   "real", "imag",  "A",  "Alpha", "AR",
                                        "RA", "AG",  "GA",   "AB",    "BA", "Depth", "Zback"};
  const char *const *names = xyz ? spatial : plain;
  const int count = xyz ? int(sizeof spatial / sizeof *spatial) : int(sizeof plain / sizeof *plain);
  for (int k = 0; k < count; ++k)
    if (same_letters(suffix, names[k])) return k;
  return 10000;
}

bool has_suffix(std::vector<Channel>::const_iterator begin,
                std::vector<Channel>::const_iterator end, const char *suffix) {
  return std::any_of(begin, end, [&](const Channel &c) { return same_letters(c.suffix, suffix); });
}

/* The file's channels as OpenImageIO 2.4 presents them (query_channels):
 * by layer, then by rank within the layer, then by suffix. */
std::vector<Channel> channels_in_order(const Imf::ChannelList &list) {
  std::vector<Channel> channels;
  for (auto it = list.begin(); it != list.end(); ++it) {
    const std::string name = it.name();
    const size_t dot = name.find_last_of('.');
    const size_t cut = dot == std::string::npos ? 0 : dot + 1;
    channels.push_back({name, name.substr(0, cut), name.substr(cut), 10000, it.channel().type,
                        it.channel().xSampling, it.channel().ySampling});
  }
  std::sort(channels.begin(), channels.end(),
            [](const Channel &a, const Channel &b) { return a.layer < b.layer; });
  for (auto begin = channels.begin(); begin != channels.end();) {
    auto end = begin;
    while (end != channels.end() && end->layer == begin->layer) ++end;
    const bool xyz =
        has_suffix(begin, end, "X") && (has_suffix(begin, end, "Y") || has_suffix(begin, end, "Z"));
    for (auto c = begin; c != end; ++c) c->special = special_index(c->suffix, xyz);
    begin = end;
  }
  std::sort(channels.begin(), channels.end(), [](const Channel &a, const Channel &b) {
    if (a.layer != b.layer) return a.layer < b.layer;
    if (a.special != b.special) return a.special < b.special;
    return a.suffix < b.suffix;
  });
  return channels;
}

/* ---- the exposure metadata, as OpenImageIO's ImageSpec holds it ---- */

/* How exrinput.cpp keeps an attribute of each OpenEXR type (parse_header),
 * and how ParamValue::get_float makes a float of it: convert_type on its
 * first element, where aggregates (v2f, m33f, box2i, ...) give nothing, and
 * so do INT values (int, keycode): OpenImageIO 2.4's to_floats has no INT
 * case, so an int attribute reads as absent (the ISO its own writer stores
 * as an int among them). */
enum class Kept { no, f32, f64, i32, u32, rational, text, texts, aggregate };

Kept kept_as(const char *type) {
  static const struct {
    const char *type;
    Kept kept;
  } table[] = {
      {"float", Kept::f32},         {"double", Kept::f64},      {"int", Kept::i32},
      {"timecode", Kept::u32},      {"keycode", Kept::i32},     {"chromaticities", Kept::f32},
      {"rational", Kept::rational}, {"string", Kept::text},     {"stringvector", Kept::texts},
      {"m33f", Kept::aggregate},    {"m44f", Kept::aggregate},  {"v3f", Kept::aggregate},
      {"v3i", Kept::aggregate},     {"v2f", Kept::aggregate},   {"v2i", Kept::aggregate},
      {"v2d", Kept::aggregate},     {"v3d", Kept::aggregate},   {"m33d", Kept::aggregate},
      {"m44d", Kept::aggregate},    {"box2i", Kept::aggregate}, {"box2f", Kept::aggregate},
      {"floatvector", Kept::f32}};
  for (const auto &row : table)
    if (std::strcmp(type, row.type) == 0) return row.kept;
  return Kept::no;
}

template <typename T>
T get_le(const std::string &bytes, size_t at) {
  T value{};
  if (bytes.size() >= at + sizeof(T)) std::memcpy(&value, bytes.data() + at, sizeof(T));
  return value;
}

/* Strutil::parse_float as convert_type uses it: leading blanks, then a
 * number that is the whole rest of the string. */
float parsed(const char *text) {
  while (*text == ' ' || (*text >= '\t' && *text <= '\r')) ++text;
  char *end = nullptr;
  const float value = std::strtof(text, &end);
  return end != text && *end == '\0' ? value : NAN;
}

/* The float OpenImageIO makes of a kept attribute (its stored bytes);
 * *kept false when exrinput.cpp would not keep it (an empty string, a
 * rational it cannot hold). */
float value_of(Kept kind, const std::string &v, bool *kept) {
  *kept = true;
  switch (kind) {
    case Kept::f32:
      return get_le<float>(v, 0);
    case Kept::f64:
      return float(get_le<double>(v, 0));
    case Kept::i32:
      return NAN; /* OpenImageIO 2.4 (above) */
    case Kept::u32:
      return float(get_le<uint32_t>(v, 0));
    case Kept::rational: {
      int64_t n = get_le<int32_t>(v, 0), d = get_le<uint32_t>(v, 4);
      if (d >= (int64_t(1) << 31)) { /* exrinput.cpp: reduced by the gcd, or dropped */
        int64_t a = std::llabs(n), b = d;
        while (b != 0) {
          const int64_t r = a % b;
          a = b;
          b = r;
        }
        if (a <= 1) return *kept = false, NAN;
        n /= a;
        d /= a;
      }
      return d ? float(n) / float(d) : 0.0f;
    }
    case Kept::text: /* kept when not empty, up to its first NUL (c_str()) */
      if (v.empty()) return *kept = false, NAN;
      return parsed(v.c_str());
    case Kept::texts: { /* the first string: its length, then its bytes */
      const int32_t length = get_le<int32_t>(v, 0);
      if (v.size() < 4 || length < 0 || size_t(length) > v.size() - 4) return NAN;
      return parsed(v.substr(4, size_t(length)).c_str());
    }
    default:
      return NAN;
  }
}

/* image_oiio_read's positive_attribute(spec, name): ImageSpec::attribute
 * lets each attribute replace an earlier one whose name matches ignoring
 * case (in the header's name order, expTime and aperture renamed
 * ExposureTime and FNumber), and get_float_attribute ignores case too. */
double exposure_value(const Imf::Header &header, const char *name) {
  float value = NAN;
  for (auto it = header.begin(); it != header.end(); ++it) {
    std::string oiio_name = it.name();
    if (oiio_name == "expTime") oiio_name = "ExposureTime";
    if (oiio_name == "aperture") oiio_name = "FNumber";
    const Kept kind = kept_as(it.attribute().typeName());
    if (kind == Kept::no || !same_letters(oiio_name, name)) continue;
    Bytes bytes;
    it.attribute().writeValueTo(bytes, 2);
    bool kept;
    const float v = value_of(kind, bytes.bytes, &kept);
    if (kept) value = v;
  }
  return std::isfinite(value) && value > 0.0f ? double(value) : NAN;
}

/* info as image_oiio_read fills it: "openexr"; the channels' merged type
 * (TypeDesc::basetype_merge: all HALF 16 bits, all UINT 32 bits integer,
 * any mix FLOAT); the exposure. */
void info_fill(cf_image_info *info, const Imf::Header &header,
               const std::vector<Channel> &channels) {
  std::snprintf(info->format, sizeof info->format, "openexr");
  bool all_half = true, all_uint = true;
  for (const Channel &c : channels) {
    all_half &= c.type == Imf::HALF;
    all_uint &= c.type == Imf::UINT;
  }
  info->bits_per_sample = all_half ? 16 : 32;
  info->is_float = !all_uint;
  info->exposure_time = exposure_value(header, "ExposureTime");
  info->f_number = exposure_value(header, "FNumber");
  info->iso = exposure_value(header, "Exif:PhotographicSensitivity");
  if (std::isnan(info->iso)) info->iso = exposure_value(header, "Exif:ISOSpeedRatings");
}

/* ---- reading ---- */

/* image_oiio_read's checks on part 0, in its order: channels OpenImageIO
 * opens (some, none subsampled), flat, the sizes accepted, whole. */
cf_status part_accept(const char *path, const Imf::Header &header,
                      const std::vector<Channel> &channels, int width, int height, cf_error *err) {
  if (channels.empty())
    return cf_error_set(err, CF_EPARSE, "%s: an OpenEXR image with no channels", path);
  for (const Channel &c : channels)
    if (c.x_sampling != 1 || c.y_sampling != 1)
      return cf_error_set(err, CF_EUNSUPPORTED,
                          "%s: channel '%s' is subsampled (%d, %d); OpenImageIO 2.4 and clayfit "
                          "read full-resolution channels only",
                          path, c.name.c_str(), c.x_sampling, c.y_sampling);
  if (header.hasType() && same_letters(header.type().substr(0, 4), "deep"))
    return cf_error_set(err, CF_EUNSUPPORTED, "%s: deep images are not supported", path);
  const Imath::Box2i data = header.dataWindow(), display = header.displayWindow();
  const int64_t w = int64_t(data.max.x) - data.min.x + 1, h = int64_t(data.max.y) - data.min.y + 1;
  if (w > INT32_MAX || h > INT32_MAX)
    return cf_error_set(err, CF_ERANGE,
                        "%s: %lld x %lld pixels, more than the 2^31 values clayfit reads", path,
                        (long long)w, (long long)h);
  cf_status s = image_header_accept(path, int(w), int(h), int(channels.size()), width, height, err);
  if (s != CF_OK) return s;
  if (data != display)
    return image_window_refuse(path, int(w), int(h), data.min.x, data.min.y,
                               int(int64_t(display.max.x) - display.min.x + 1),
                               int(int64_t(display.max.y) - display.min.y + 1), display.min.x,
                               display.min.y, err);
  return CF_OK;
}

/* Every channel decoded into `pixels` (interleaved in `channels`' order):
 * HALF and FLOAT as float by OpenEXR (Imath's exact half to float), UINT
 * as stored, then scaled in place as OpenImageIO's convert_type<uint32_t,
 * float> does: float(v) * (1.0f / 4294967295.0f). */
void decode(Imf::MultiPartInputFile &file, const std::vector<Channel> &channels, float *pixels) {
  Imf::InputPart part(file, 0);
  const Imath::Box2i window = part.header().dataWindow();
  const size_t n = channels.size(), x_stride = n * sizeof(float);
  const size_t y_stride = x_stride * size_t(window.max.x - window.min.x + 1);
  Imf::FrameBuffer buffer;
  for (size_t c = 0; c < n; ++c) {
    const Imf::PixelType type = channels[c].type == Imf::UINT ? Imf::UINT : Imf::FLOAT;
    buffer.insert(channels[c].name, Imf::Slice::Make(type, pixels + c, window, x_stride, y_stride));
  }
  part.setFrameBuffer(buffer);
  part.readPixels(window.min.y, window.max.y);
  const size_t values = y_stride / sizeof(float) * size_t(window.max.y - window.min.y + 1);
  for (size_t c = 0; c < n; ++c) {
    if (channels[c].type != Imf::UINT) continue;
    for (size_t k = c; k < values; k += n) {
      uint32_t stored;
      std::memcpy(&stored, pixels + k, sizeof stored);
      pixels[k] = float(stored) * (1.0f / 4294967295.0f);
    }
  }
}

/* image_exr_read's body; *decoding tells the caller an exception came
 * from the pixels, not the header. */
cf_status read_exr(const char *path, FILE *file, int width, int height, cf_image_header *header,
                   cf_image *image, bool *decoding, cf_error *err) {
  if (std::fseek(file, 0, SEEK_SET) != 0)
    return cf_error_set(err, CF_EIO, "%s: cannot read it: %s", path, std::strerror(errno));
  FileIn stream(path, file);
  Imf::MultiPartInputFile input(stream, kThreads);
  const Imf::Header &part = input.header(0);
  const std::vector<Channel> channels = channels_in_order(part.channels());
  cf_status s = part_accept(path, part, channels, width, height, err);
  if (s != CF_OK) return s;
  const Imath::Box2i window = part.dataWindow();
  header->width = window.max.x - window.min.x + 1;
  header->height = window.max.y - window.min.y + 1;
  header->channels = int(channels.size());
  info_fill(&header->info, part, channels);
  if (!image) return CF_OK;
  s = cf_image_alloc(image, header->width, header->height, header->channels, err);
  if (s != CF_OK) {
    cf_error_prefix(err, "%s", path);
    return s;
  }
  *decoding = true;
  decode(input, channels, image->pixels);
  return CF_OK;
}

/* An exception's message on one line. */
std::string one_line(const char *what) {
  std::string text = what && *what ? what : "no details from OpenEXR";
  for (char &c : text)
    if (c == '\n' || c == '\r') c = ' ';
  while (!text.empty() && (text.back() == ' ' || text.back() == '.')) text.pop_back();
  return text;
}

/* ---- writing ---- */

/* image_oiio_write's channel names (ImageSpec's defaults, as its OpenEXR
 * writer stores them): Y; R, G; R, G, B; R, G, B, A. */
const char *channel_name(int channels, int c) {
  static const char *const rgba[4] = {"R", "G", "B", "A"};
  return channels == 1 ? "Y" : rgba[c];
}

/* image_exr_write's body: the header image_oiio_write writes (ZIP,
 * INCREASING_Y scan lines, whole) with info's exposure under the names its
 * writer gives them (expTime, aperture, Exif:PhotographicSensitivity), all
 * float: image_oiio_write's int ISO (rounded) reads back as absent through
 * OpenImageIO 2.4 (exposure_value), a float one through both readers. */
cf_status write_exr(const char *path, const cf_image *image, int bits, const cf_image_info *info,
                    cf_error *err) {
  const Imf::PixelType type = bits == 16 ? Imf::HALF : Imf::FLOAT;
  Imf::Header header(image->width, image->height, 1.0f, Imath::V2f(0, 0), 1.0f, Imf::INCREASING_Y,
                     Imf::ZIP_COMPRESSION);
  const size_t n = size_t(image->channels), values = size_t(image->width) * image->height * n;
  for (size_t c = 0; c < n; ++c)
    header.channels().insert(channel_name(int(n), int(c)), Imf::Channel(type));
  if (info && std::isfinite(info->exposure_time))
    header.insert("expTime", Imf::FloatAttribute(float(info->exposure_time)));
  if (info && std::isfinite(info->f_number))
    header.insert("aperture", Imf::FloatAttribute(float(info->f_number)));
  if (info && std::isfinite(info->iso) && std::fabs(info->iso) < 2147483647.0)
    header.insert("Exif:PhotographicSensitivity",
                  Imf::FloatAttribute(float(std::lround(info->iso))));
  std::vector<half> halves(type == Imf::HALF ? values : 0);
  for (size_t k = 0; k < halves.size(); ++k)
    halves[k] = half(image->pixels[k]); /* Imath's
                  rounding, as OpenImageIO's */
  const size_t size = type == Imf::HALF ? sizeof(half) : sizeof(float);
  const char *base = type == Imf::HALF ? reinterpret_cast<const char *>(halves.data())
                                       : reinterpret_cast<const char *>(image->pixels);
  Imf::FrameBuffer buffer;
  for (size_t c = 0; c < n; ++c)
    buffer.insert(channel_name(int(n), int(c)),
                  Imf::Slice(type, const_cast<char *>(base + c * size), n * size,
                             n * size * size_t(image->width)));
  std::unique_ptr<FILE, int (*)(FILE *)> file(std::fopen(path, "wb"), std::fclose);
  if (!file)
    return cf_error_set(err, CF_EIO, "%s: cannot create the file: %s", path, std::strerror(errno));
  FileOut stream(path, file.get());
  {
    Imf::OutputFile output(stream, header, kThreads);
    output.setFrameBuffer(buffer);
    output.writePixels(image->height);
  } /* the offset table is written here */
  const int flushed = std::fflush(file.get()) == 0 && !std::ferror(file.get()) ? 0 : errno;
  const int closed = std::fclose(file.release()) == 0 ? 0 : errno;
  const int failed = stream.failed ? stream.failed : flushed ? flushed : closed;
  if (stream.failed || flushed || closed)
    return cf_error_set(err, CF_EIO, "%s: could not write the image: %s", path,
                        std::strerror(failed ? failed : EIO));
  return CF_OK;
}

}  // namespace

extern "C" {

cf_status image_exr_read(const char *path, FILE *file, long long size, int width, int height,
                         cf_image_header *header, cf_image *image, cf_error *err) {
  (void)size; /* the stream's reads fail at the end of the file */
  bool decoding = false;
  try {
    return read_exr(path, file, width, height, header, image, &decoding, err);
  } catch (const std::bad_alloc &) {
    if (image) cf_image_free(image);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while decoding it", path);
  } catch (const std::exception &e) {
    if (image) cf_image_free(image);
    if (decoding)
      return cf_error_set(err, CF_EIO, "%s: cannot read the pixels: %s", path,
                          one_line(e.what()).c_str());
    return cf_error_set(err, CF_EPARSE, "%s: cannot read its OpenEXR header: %s", path,
                        one_line(e.what()).c_str());
  } catch (...) {
    if (image) cf_image_free(image);
    return cf_error_set(err, CF_EIO, "%s: reading failed (an unknown exception)", path);
  }
}

cf_status image_exr_write(const char *path, const cf_image *image, int bits,
                          const cf_image_info *info, cf_error *err) {
  try {
    return write_exr(path, image, bits, info, err);
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while writing it", path);
  } catch (const std::exception &e) {
    return cf_error_set(err, CF_EIO, "%s: could not write the image: %s", path,
                        one_line(e.what()).c_str());
  } catch (...) {
    return cf_error_set(err, CF_EIO, "%s: writing failed (an unknown exception)", path);
  }
}

}  // extern "C"
