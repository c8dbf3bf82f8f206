/* OpenEXR files test_image_exr makes with OpenEXR's own API (what
 * image_oiio_write cannot write): tiles and MIP maps, several parts, any
 * channel names and types, data windows, deep data, attributes of any
 * type. C interface over exr_fixtures.cpp. */
#ifndef CLAYFIT_TEST_EXR_FIXTURES_H
#define CLAYFIT_TEST_EXR_FIXTURES_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct exr_fixture {
  int width, height;
  const char *channels;   /* names and types: "R:h G:h B:f A:u" (half, float, uint) */
  int tile;               /* tile size; 0: scan lines */
  int mipmap;             /* tiles in MIP-map levels */
  int x, y;               /* the data window's origin (the display window's too) */
  int display_shift;      /* the display window moved this far right of the data window */
  int compression;        /* OpenEXR's Compression (0 none, 3 ZIP, 4 PIZ, ...) */
  int parts;              /* 2: a second part, tiled, with other channels */
  int subsampled;         /* the last channel has one sample per 2 x 2 pixels */
  int deep;               /* deep scan lines, one sample a pixel */
  const char *attributes; /* "name:type=value;...": float, double, int, string,
                             rational (n/d), v2f (a,b), stringvector, chromaticities,
                             floatvector, timecode */
  unsigned seed;          /* the samples: every bit pattern of their type, from this */
} exr_fixture;

/* 0, or -1 with OpenEXR's message in why. */
int exr_fixture_write(const char *path, const exr_fixture *fixture, char *why, int why_size);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_TEST_EXR_FIXTURES_H */
