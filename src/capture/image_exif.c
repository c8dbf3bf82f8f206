/* The EXIF block of a JPEG's APP1 segment (image_codec.h): its TIFF
 * structure read for three tags and written with them. CIPA DC-008
 * (Exif 2.32) §4.6: a TIFF header ("II" or "MM", 42, the offset of IFD0),
 * IFD0 pointing to the Exif SubIFD by tag 0x8769, 12-byte entries (tag,
 * type, count, a value of at most 4 bytes or the offset of a longer one),
 * every offset from the TIFF header's first byte. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "image_codec.h"

enum {
  TAG_EXPOSURE_TIME = 0x829A,
  TAG_F_NUMBER = 0x829D,
  TAG_ISO = 0x8827, /* PhotographicSensitivity, formerly ISOSpeedRatings */
  TAG_EXIF_IFD = 0x8769,
  TAG_INTEROPERABILITY_IFD = 0xA005,
  TYPE_SHORT = 3,
  TYPE_LONG = 4,
  TYPE_RATIONAL = 5,
  TYPE_SRATIONAL = 10,
  ENTRY_BYTES = 12,
  /* the IFDs one block may chain: IFD0, the Exif SubIFD, its
     interoperability IFD, with room to spare; each visited once */
  MOST_IFDS = 8
};

/* ---- reading ---- */

typedef struct exif_reader {
  const unsigned char *tiff;
  size_t size;
  int big_endian;
  uint32_t seen[MOST_IFDS]; /* IFD offsets visited, against loops */
  int seen_count;
  cf_image_info *info;
} exif_reader;

static uint32_t u16_at(const exif_reader *r, size_t at) {
  const unsigned char *b = r->tiff + at;
  return r->big_endian ? (uint32_t)b[0] << 8 | b[1] : (uint32_t)b[1] << 8 | b[0];
}

static uint32_t u32_at(const exif_reader *r, size_t at) {
  const unsigned char *b = r->tiff + at;
  return r->big_endian ? (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3]
                       : (uint32_t)b[3] << 24 | (uint32_t)b[2] << 16 | (uint32_t)b[1] << 8 | b[0];
}

/* Where an entry's value of count items of item_bytes each lies: in the
 * entry itself when it fits in 4 bytes, else at its offset; SIZE_MAX when
 * it does not lie wholly inside the block (count × item_bytes in 64 bits: a count
 * is at most 2^32 − 1 and an item 8 bytes, so no overflow). */
static size_t value_at(const exif_reader *r, size_t entry, uint32_t count, int item_bytes) {
  const uint64_t bytes = (uint64_t)count * (uint64_t)item_bytes;
  if (bytes <= 4) return entry + 8;
  const uint64_t offset = u32_at(r, entry + 8);
  if (offset + bytes > r->size) return SIZE_MAX;
  return (size_t)offset;
}

/* A field's first value as OpenImageIO 2.4 reads it (exif.cpp,
 * add_exif_item_to_spec, by the field's own type whatever the tag's, then
 * ImageSpec::get_float_attribute): SHORT, LONG, or (S)RATIONAL as
 * (float)((double)num / (double)den). The fit multiplies exposures made
 * of these floats, so they must be the same floats; a zero denominator
 * gives inf or NaN, which the caller refuses. 0 (and no value, as
 * OpenImageIO sets none) for another type or a value outside the block. */
static int first_value(const exif_reader *r, size_t entry, uint32_t type, uint32_t count,
                       double *value) {
  /* a BYTE gives OpenImageIO 2.4.7 no value (tests/capture/test_image_jpeg.c) */
  static const int item_bytes[11] = {0, 0, 0, 2, 4, 8, 0, 0, 0, 0, 8};
  if (count < 1 || type > 10 || !item_bytes[type]) return 0;
  const size_t at = value_at(r, entry, count, item_bytes[type]);
  if (at == SIZE_MAX) return 0;
  const uint32_t a = type == TYPE_SHORT ? u16_at(r, at) : u32_at(r, at);
  if (type == TYPE_RATIONAL)
    *value = (double)(float)((double)a / (double)u32_at(r, at + 4));
  else if (type == TYPE_SRATIONAL)
    *value = (double)(float)((double)(int32_t)a / (double)(int32_t)u32_at(r, at + 4));
  else
    *value = (double)(float)a;
  return 1;
}

/* A value for info: finite and positive, else NaN (EXIF's 0 is "unknown"). */
static double positive(double value) {
  return isfinite(value) && value > 0.0 ? value : NAN;
}

static void read_ifd(exif_reader *r, uint32_t offset, int depth);

/* One IFD entry: a tag of ours (a later one replaces an earlier one, as
 * in OpenImageIO, which stores each as an attribute), or a pointer to the
 * Exif SubIFD or its interoperability IFD (OpenImageIO reads both with
 * the Exif tag table, so our tags count there too). A field of a type
 * first_value does not take is skipped. */
static void read_entry(exif_reader *r, size_t entry, int depth) {
  const uint32_t tag = u16_at(r, entry), type = u16_at(r, entry + 2);
  const uint32_t count = u32_at(r, entry + 4);
  double *field = tag == TAG_EXPOSURE_TIME ? &r->info->exposure_time
                  : tag == TAG_F_NUMBER    ? &r->info->f_number
                  : tag == TAG_ISO         ? &r->info->iso
                                           : NULL;
  if (tag == TAG_EXIF_IFD || tag == TAG_INTEROPERABILITY_IFD) {
    read_ifd(r, u32_at(r, entry + 8), depth + 1);
  } else if (field) {
    double value;
    if (first_value(r, entry, type, count, &value)) *field = positive(value);
  }
}

/* The IFD at offset: each entry inside the block read, once per IFD (a
 * pointer back to a visited IFD is ignored), at most MOST_IFDS IFDs. */
static void read_ifd(exif_reader *r, uint32_t offset, int depth) {
  if (depth >= MOST_IFDS || r->seen_count >= MOST_IFDS) return;
  if ((uint64_t)offset + 2 > r->size) return;
  for (int i = 0; i < r->seen_count; ++i)
    if (r->seen[i] == offset) return;
  r->seen[r->seen_count++] = offset;
  const uint32_t entries = u16_at(r, offset);
  for (uint32_t d = 0; d < entries; ++d) {
    const uint64_t entry = (uint64_t)offset + 2 + (uint64_t)d * ENTRY_BYTES;
    /* OpenImageIO skips an entry that ends at the block's last byte or
       beyond (exif.cpp, read_exif_tag: >=); a real IFD is followed by
       its next-IFD offset, so this loses nothing */
    if (entry + ENTRY_BYTES >= r->size) return;
    read_entry(r, (size_t)entry, depth);
  }
}

void image_exif_read(const unsigned char *tiff, size_t size, cf_image_info *info) {
  if (!tiff || size < 8) return;
  exif_reader r = {.tiff = tiff, .size = size, .info = info};
  if (tiff[0] == 'M' && tiff[1] == 'M')
    r.big_endian = 1;
  else if (!(tiff[0] == 'I' && tiff[1] == 'I'))
    return;
  /* the 42 of the header is not checked: OpenImageIO does not either */
  read_ifd(&r, u32_at(&r, 4), 0);
}

/* ---- writing ---- */

#define MOST_U32 4294967295.0

/* value as num / 10^k (k <= 9, the most digits that fit 32 bits) or, for
 * small values, as 10^k / den (den the inverse's digits); whichever is
 * nearer. */
static void decimal_rational(double value, uint32_t *num, uint32_t *den) {
  double best = HUGE_VAL;
  for (int k = 9; k >= 0; --k) {
    const double scale = pow(10.0, k), a = round(value * scale), b = round(scale / value);
    if (a >= 1.0 && a <= MOST_U32 && fabs(a / scale - value) < best)
      best = fabs(a / scale - value), *num = (uint32_t)a, *den = (uint32_t)scale;
    if (b >= 1.0 && b <= MOST_U32 && fabs(scale / b - value) < best)
      best = fabs(scale / b - value), *num = (uint32_t)scale, *den = (uint32_t)b;
  }
  while (*num % 10 == 0 && *den % 10 == 0) *num /= 10, *den /= 10;
}

/* value as num / den: 1 / N when 1 / value is within 1e-9 relative of an
 * integer N (exposure times are 1/N s: exact, unlike OpenImageIO 2.4's
 * float_to_rational, which writes 1/64 as 1/0), else decimal_rational,
 * keeping at least 9 significant digits (a float's round trip) from 1e-9
 * to 4e9, fewer down to 1 / (2^32 - 1). Returns 0 when value cannot be
 * written (not finite, not positive, or out of that range). */
static int rational_of(double value, uint32_t *num, uint32_t *den) {
  if (!(isfinite(value) && value >= 1.0 / MOST_U32 && value <= MOST_U32)) return 0;
  const double inverse = 1.0 / value, n = round(inverse);
  if (n >= 1.0 && n <= MOST_U32 && fabs(inverse - n) <= 1e-9 * inverse) {
    *num = 1, *den = (uint32_t)n;
    return 1;
  }
  decimal_rational(value, num, den);
  return 1;
}

static void put16(unsigned char *b, uint32_t v) {
  b[0] = (unsigned char)v, b[1] = (unsigned char)(v >> 8);
}

static void put32(unsigned char *b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[i] = (unsigned char)(v >> (8 * i));
}

static void put_entry(unsigned char *b, uint32_t tag, uint32_t type, uint32_t count,
                      uint32_t value) {
  put16(b, tag), put16(b + 2, type), put32(b + 4, count), put32(b + 8, value);
}

/* The layout, little-endian: header (8) | IFD0: 1 entry, next 0 (18) |
 * SubIFD: n entries, next 0 (2 + 12 n + 4) | the rationals (8 each). */
size_t image_exif_write(const cf_image_info *info, unsigned char *out, size_t capacity) {
  if (!info) return 0;
  uint32_t num[2], den[2];
  const int has_time = rational_of(info->exposure_time, &num[0], &den[0]);
  const int has_f = rational_of(info->f_number, &num[1], &den[1]);
  const double iso = round(info->iso);
  const int has_iso = isfinite(info->iso) && iso >= 1.0 && iso <= MOST_U32;
  const uint32_t entries = (uint32_t)(has_time + has_f + has_iso);
  if (entries == 0) return 0;
  const size_t sub = 8 + 18, data = sub + 2 + ENTRY_BYTES * entries + 4;
  const size_t size = data + 8 * (size_t)(has_time + has_f);
  if (!out || capacity < size) return 0;
  memset(out, 0, size);
  memcpy(out, "II*\0", 4);
  put32(out + 4, 8);
  put16(out + 8, 1);
  put_entry(out + 10, TAG_EXIF_IFD, TYPE_LONG, 1, (uint32_t)sub);
  put16(out + sub, entries);
  unsigned char *entry = out + sub + 2; /* in increasing tag order (TIFF 6.0 §2) */
  size_t at = data;
  for (int i = 0; i < 2; ++i) {
    if (!(i == 0 ? has_time : has_f)) continue;
    put_entry(entry, i == 0 ? TAG_EXPOSURE_TIME : TAG_F_NUMBER, TYPE_RATIONAL, 1, (uint32_t)at);
    put32(out + at, num[i]), put32(out + at + 4, den[i]);
    entry += ENTRY_BYTES, at += 8;
  }
  /* a SHORT, as OpenImageIO 2.4 writes it (its Exif tag table's type),
     or a LONG above 65535 (which OpenImageIO would wrap) */
  if (has_iso) put_entry(entry, TAG_ISO, iso <= 65535.0 ? TYPE_SHORT : TYPE_LONG, 1, (uint32_t)iso);
  return size;
}
