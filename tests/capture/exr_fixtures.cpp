/* test_image_exr's OpenEXR files, made with OpenEXR's C++ API
 * (exr_fixtures.h). Samples are random bit patterns of each channel's type
 * (NaNs, infinities and denormals included), so a reader that converts
 * anything but exactly shows. */
#include "exr_fixtures.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfChromaticitiesAttribute.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineOutputFile.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFloatVectorAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfRationalAttribute.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfStringVectorAttribute.h>
#include <OpenEXR/ImfTiledOutputPart.h>
#include <OpenEXR/ImfTimeCodeAttribute.h>
#include <OpenEXR/ImfVecAttribute.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Plane {
  std::string name;
  Imf::PixelType type;
  std::vector<uint32_t> samples; /* one 32-bit word a sample; HALF uses the low 16 bits */
};

uint32_t next(uint32_t &state) { /* xorshift32 */
  state ^= state << 13;
  state ^= state >> 17;
  state ^= state << 5;
  return state;
}

std::vector<Plane> planes(const exr_fixture &f, size_t count) {
  std::vector<Plane> out;
  std::istringstream list(f.channels);
  uint32_t state = f.seed ? f.seed : 1u;
  for (std::string item; list >> item;) {
    const size_t colon = item.rfind(':');
    const char t = item[colon + 1];
    Plane p{item.substr(0, colon), t == 'u' ? Imf::UINT : t == 'f' ? Imf::FLOAT : Imf::HALF, {}};
    p.samples.resize(count);
    for (uint32_t &s : p.samples) s = p.type == Imf::HALF ? next(state) & 0xffffu : next(state);
    out.push_back(p);
  }
  return out;
}

void add_attribute(Imf::Header &h, const std::string &item) {
  /* names may hold a colon ("Exif:..."): the type follows the last colon before '=' */
  const size_t eq = item.find('='), type_at = item.rfind(':', eq);
  const std::string name = item.substr(0, type_at),
                    type = item.substr(type_at + 1, eq - type_at - 1);
  const std::string value = item.substr(eq + 1);
  const char *v = value.c_str();
  if (type == "float")
    h.insert(name, Imf::FloatAttribute(std::strtof(v, nullptr)));
  else if (type == "double")
    h.insert(name, Imf::DoubleAttribute(std::strtod(v, nullptr)));
  else if (type == "int")
    h.insert(name, Imf::IntAttribute(int(std::strtol(v, nullptr, 10))));
  else if (type == "string")
    h.insert(name, Imf::StringAttribute(value));
  else if (type == "stringvector")
    h.insert(name, Imf::StringVectorAttribute({value, "9"}));
  else if (type == "rational") {
    char *end;
    const long n = std::strtol(v, &end, 10);
    const unsigned long d = std::strtoul(end + 1, nullptr, 10);
    h.insert(name, Imf::RationalAttribute(Imf::Rational(int(n), (unsigned)d)));
  } else if (type == "v2f") {
    char *end;
    const float a = std::strtof(v, &end);
    h.insert(name, Imf::V2fAttribute(Imath::V2f(a, std::strtof(end + 1, nullptr))));
  } else if (type == "chromaticities") {
    Imf::Chromaticities c;
    c.red.x = std::strtof(v, nullptr);
    h.insert(name, Imf::ChromaticitiesAttribute(c));
  } else if (type == "floatvector") {
    h.insert(name, Imf::FloatVectorAttribute({std::strtof(v, nullptr), 7.0f}));
  } else if (type == "timecode") {
    h.insert(name, Imf::TimeCodeAttribute(Imf::TimeCode(unsigned(std::strtoul(v, nullptr, 10)))));
  } else {
    throw std::runtime_error("unknown attribute type " + type);
  }
}

Imf::Header header_of(const exr_fixture &f, const std::vector<Plane> &p) {
  Imath::Box2i data(Imath::V2i(f.x, f.y), Imath::V2i(f.x + f.width - 1, f.y + f.height - 1));
  Imath::Box2i display = data;
  display.min.x += f.display_shift;
  display.max.x += f.display_shift;
  Imf::Header h(display, data);
  h.compression() = Imf::Compression(f.compression);
  for (size_t c = 0; c < p.size(); ++c) {
    const int s = f.subsampled && c + 1 == p.size() ? 2 : 1;
    h.channels().insert(p[c].name, Imf::Channel(p[c].type, s, s));
  }
  if (f.tile)
    h.setTileDescription(Imf::TileDescription(unsigned(f.tile), unsigned(f.tile),
                                              f.mipmap ? Imf::MIPMAP_LEVELS : Imf::ONE_LEVEL));
  if (f.attributes) {
    std::istringstream list(f.attributes);
    for (std::string item; std::getline(list, item, ';');)
      if (!item.empty()) add_attribute(h, item);
  }
  return h;
}

void write_flat(Imf::MultiPartOutputFile &file, int part, const exr_fixture &f,
                std::vector<Plane> &p, bool tiled) {
  /* HALF samples packed into 16-bit words */
  std::vector<std::vector<uint16_t>> halves(p.size());
  Imf::FrameBuffer fb;
  Imath::Box2i data(Imath::V2i(f.x, f.y), Imath::V2i(f.x + f.width - 1, f.y + f.height - 1));
  for (size_t c = 0; c < p.size(); ++c) {
    const int s = f.subsampled && c + 1 == p.size() ? 2 : 1;
    void *base = p[c].samples.data();
    size_t size = 4;
    if (p[c].type == Imf::HALF) {
      halves[c].assign(p[c].samples.begin(), p[c].samples.end());
      base = halves[c].data();
      size = 2;
    }
    /* a subsampled plane is addressed by pixel coordinates / s: stride s x */
    fb.insert(p[c].name,
              Imf::Slice::Make(p[c].type, base, data, size, size * size_t(f.width), s, s));
  }
  if (tiled) {
    Imf::TiledOutputPart out(file, part);
    out.setFrameBuffer(fb);
    for (int level = 0; level < out.numLevels(); ++level) /* every level holds level 0's
                                                             samples: only 0 is read */
      out.writeTiles(0, out.numXTiles(level) - 1, 0, out.numYTiles(level) - 1, level);
  } else {
    Imf::OutputPart out(file, part);
    out.setFrameBuffer(fb);
    out.writePixels(f.height);
  }
}

void write_deep(const char *path, const exr_fixture &f) {
  Imf::Header h(f.width, f.height);
  h.channels().insert("Z", Imf::Channel(Imf::FLOAT));
  h.setType(Imf::DEEPSCANLINE);
  h.compression() = Imf::ZIPS_COMPRESSION;
  std::vector<unsigned> counts(size_t(f.width) * f.height, 1u);
  std::vector<float> z(counts.size(), 1.0f);
  std::vector<float *> pointers(counts.size());
  for (size_t k = 0; k < z.size(); ++k) pointers[k] = &z[k];
  Imf::DeepFrameBuffer fb;
  fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, (char *)counts.data(), sizeof(unsigned),
                                       sizeof(unsigned) * size_t(f.width)));
  fb.insert("Z", Imf::DeepSlice(Imf::FLOAT, (char *)pointers.data(), sizeof(float *),
                                sizeof(float *) * size_t(f.width), sizeof(float)));
  Imf::DeepScanLineOutputFile out(path, h);
  out.setFrameBuffer(fb);
  out.writePixels(f.height);
}

void write_fixture(const char *path, const exr_fixture &f) {
  if (f.deep) return write_deep(path, f);
  std::vector<Plane> p = planes(f, size_t(f.width) * size_t(f.height));
  std::vector<Imf::Header> headers{header_of(f, p)};
  exr_fixture second = f;
  second.channels = "R:f G:f B:f";
  second.tile = 8;
  second.seed = f.seed * 7 + 3;
  second.attributes = nullptr;
  second.subsampled = 0;
  std::vector<Plane> q = planes(second, size_t(f.width) * size_t(f.height));
  headers[0].setType(f.tile ? Imf::TILEDIMAGE : Imf::SCANLINEIMAGE);
  if (f.parts == 2) {
    headers.push_back(header_of(second, q));
    headers[0].setName("first");
    headers[1].setName("second");
    headers[1].setType(Imf::TILEDIMAGE);
  }
  Imf::MultiPartOutputFile file(path, headers.data(), int(headers.size()));
  write_flat(file, 0, f, p, f.tile != 0);
  if (f.parts == 2) write_flat(file, 1, second, q, true);
}

}  // namespace

extern "C" int exr_fixture_write(const char *path, const exr_fixture *fixture, char *why,
                                 int why_size) {
  try {
    write_fixture(path, *fixture);
    return 0;
  } catch (const std::exception &e) {
    std::snprintf(why, size_t(why_size), "%s", e.what());
    return -1;
  }
}
