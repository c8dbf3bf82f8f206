/* Every image's pixels into observations (capture_internal.h): an image
 * (decoding its file and mask, its observations) needs nothing from the
 * others, so WORKERS parts of core's thread pool read images side by side,
 * each into its part's own arrays, then copied to the capture's after the
 * previous image's (their place is known once the previous images' counts
 * are): the order is the images'. Then, in image order, each image's checks
 * and warnings: the first error in image order is the one reported, as if
 * the images were read one by one. One mask file for every image
 * (DiLiGenT's) is decoded once. */
#define _POSIX_C_SOURCE 200809L /* stat, dev_t, ino_t */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "capture_internal.h"
#include "core/parallel.h"

/* 2 parts on 2 cores: the demo loaded in 0.51 of one part's wall time (5
 * alternating runs of a program loading it, busy machine) */
enum { WORKERS = 2 };

/* What reading image k gave, for the accounting in image order. */
typedef struct image_slot {
  cf_status status; /* decoding the image and its mask */
  cf_error err;
  int width, height, channels;
  int mask_empty; /* its own mask has no usable pixel */
  cf_status exposure_status;
  cf_error exposure_err;
  double exposure;
  int jpeg;
  cf_status coding_status; /* of a JPEG's coding */
  cf_error coding_err;
  cf_jpeg_coding coding;
  size_t bound; /* pixels in its capture_surface_bounds */
  image_observations added;
} image_slot;

typedef struct read_images {
  cf_capture *capture;
  image_slot *slots; /* one per image */
  /* one mask for every image: decoded once (its status and error stand
   * for each image's) */
  int one_mask;
  cf_image shared_mask;
  cf_status shared_status;
  cf_error shared_err;
  size_t count, next;  /* images; the next to read */
  size_t first_failed; /* the first image that failed (count: none) */
  size_t placed;       /* images whose observations have their place */
  size_t most;         /* the largest bound */
  pthread_mutex_t lock;
  pthread_cond_t changed;
  const cf_capture_options *options;
} read_images;

static cf_status check_mask(const cf_capture *capture, size_t k, const cf_image *image,
                            const cf_image *mask, cf_error *err) {
  if (mask->width == image->width && mask->height == image->height) return CF_OK;
  return cf_error_set(err, CF_EINVAL, "%s: the mask is %d x %d pixels but %s is %d x %d",
                      capture->spec.mask_paths[k], mask->width, mask->height,
                      capture->spec.image_paths[k], image->width, image->height);
}

/* 1 if no pixel of the mask is usable (capture_mask_usable). */
static int mask_is_empty(const cf_image *mask) {
  const size_t pixels = (size_t)mask->width * (size_t)mask->height;
  for (size_t i = 0; i < pixels; ++i)
    if (capture_mask_usable(mask->pixels[i * (size_t)mask->channels])) return 0;
  return 1;
}

/* Image k's own mask, or the one every image shares. */
static const cf_image *mask_of(const read_images *r, const cf_image *own) {
  if (!r->capture->spec.mask_paths) return NULL;
  return r->one_mask ? &r->shared_mask : own;
}

/* Image k's pixels and mask (reads only the capture's file names and the
 * shared mask). */
static void decode(const read_images *r, size_t k, image_slot *d, cf_image *image,
                   cf_image *mask, cf_image_info *info) {
  const cf_capture *capture = r->capture;
  const cf_capture_spec *spec = &capture->spec;
  /* the size its header declared when the headers were read (it must
   * not have changed since) */
  const int width = capture->images[k].width, height = capture->images[k].height;
  d->status = cf_image_read_sized(spec->image_paths[k], width, height, image, info, &d->err);
  if (d->status == CF_OK && info->is_float) /* integer samples are finite */
    d->status = cf_image_check_finite(image, spec->image_paths[k], &d->err);
  d->width = image->width, d->height = image->height, d->channels = image->channels;
  if (d->status != CF_OK || !spec->mask_paths) return;
  if (!r->one_mask) {
    d->status = cf_image_read_sized(spec->mask_paths[k], width, height, mask, NULL, &d->err);
    if (d->status == CF_OK) d->mask_empty = mask_is_empty(mask);
  } else if (r->shared_status != CF_OK) {
    d->status = r->shared_status;
    d->err = r->shared_err;
  }
  if (d->status == CF_OK) d->status = check_mask(capture, k, image, mask_of(r, mask), &d->err);
}

/* Image k read whole: decoded, its exposure, a JPEG's coding and its
 * observations into `own` (reads the capture, writes only its slot). */
static void read_image(read_images *r, size_t k, cf_observations *own) {
  const cf_capture *capture = r->capture;
  image_slot *d = &r->slots[k];
  cf_image image = {0}, mask = {0};
  cf_image_info info;
  memset(&info, 0, sizeof info);
  decode(r, k, d, &image, &mask, &info);
  if (d->status == CF_OK)
    d->exposure_status = capture_raw_exposure(capture, k, &info, &d->exposure, &d->exposure_err);
  if (d->status == CF_OK && d->exposure_status == CF_OK) {
    d->jpeg = strcmp(info.format, "jpeg") == 0;
    if (d->jpeg)
      d->coding_status = cf_jpeg_coding_read(capture->spec.image_paths[k], &d->coding,
                                             &d->coding_err);
    cf_decode decoding = capture_image_decode(capture, &info, d->exposure);
    const int eight_bit = !info.is_float && info.bits_per_sample == 8;
    capture_add_observations(capture, k, &image, mask_of(r, &mask), &decoding, eight_bit, own,
                             &d->added);
  }
  cf_image_free(&image);
  cf_image_free(&mask);
}

/* Image k's observations (in `own`) to their place in the capture's
 * arrays, after the previous images' (which may be copied at the same
 * time: the places do not overlap). Called with the lock held. */
static void place(read_images *r, size_t k, const cf_observations *own) {
  while (r->placed < k) pthread_cond_wait(&r->changed, &r->lock);
  cf_observations *o = &r->capture->obs;
  const size_t at = o->count;
  o->count += own->count;
  r->placed = k + 1;
  pthread_cond_broadcast(&r->changed);
  pthread_mutex_unlock(&r->lock);
  capture_move_observations(o, at, own, 0, own->count);
  pthread_mutex_lock(&r->lock);
}

/* One part's share: the next image not read, until there is none or one
 * before it failed; its observations go through the part's own arrays
 * (their place is known only when the previous images' counts are).
 * Part 0 (this thread) reports the progress. */
static void read_part(void *user, int part) {
  read_images *r = user;
  const cf_capture_options *options = r->options;
  cf_observations own = {0, r->capture->obs.lights, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
  cf_error err;
  const int room = capture_allocate_observations(&own, r->most, &err) == CF_OK;
  pthread_mutex_lock(&r->lock);
  while (r->next < r->count && r->next < r->first_failed) {
    size_t k = r->next++;
    if (part == 0 && options && options->progress)
      options->progress(options->progress_user, "reading images", k, r->count);
    pthread_mutex_unlock(&r->lock);
    own.count = 0;
    if (room)
      read_image(r, k, &own);
    else
      r->slots[k].status = cf_error_set(&r->slots[k].err, CF_ENOMEM,
                                        "out of memory for %zu observations", r->most);
    const int failed = r->slots[k].status != CF_OK || r->slots[k].exposure_status != CF_OK;
    pthread_mutex_lock(&r->lock);
    if (failed && k < r->first_failed) r->first_failed = k;
    place(r, k, &own);
  }
  pthread_mutex_unlock(&r->lock);
  capture_free_observations(&own);
}

/* A JPEG's coding, for the fit's model of its error: a file whose markers
 * cannot be read is fitted without that model, and the capture says so. */
static void set_jpeg_coding(cf_capture *capture, size_t k, const image_slot *d) {
  cf_capture_image *image = &capture->images[k];
  if (d->coding_status != CF_OK) {
    capture_warn(capture, "%s; its JPEG coding error is not modelled", d->coding_err.message);
    return;
  }
  image->jpeg_quality = d->coding.quality;
  image->jpeg_exact = d->coding.exact;
  image->jpeg_chroma = (int)d->coding.chroma;
}

/* Image k's part in the capture, its checks and warnings, in image order
 * (as if the images were read one by one). */
static cf_status account(cf_capture *capture, size_t k, const image_slot *d, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  if (d->status != CF_OK) {
    *err = d->err;
    return d->status;
  }
  cf_image as_decoded = {d->width, d->height, d->channels, NULL};
  cf_status s = capture_check_size(capture, k, &as_decoded, err);
  if (s == CF_OK && capture->normal_map.pixels &&
      (capture->normal_map.width != d->width || capture->normal_map.height != d->height))
    s = cf_error_set(err, CF_EINVAL, "%s: the normal map is %d x %d pixels but %s is %d x %d",
                     spec->normal_map, capture->normal_map.width, capture->normal_map.height,
                     spec->image_paths[k], d->width, d->height);
  if (s == CF_OK && d->mask_empty)
    capture_warn(capture,
                 "%s: no pixel of this mask is usable (all are 0.5 or less), so %s adds "
                 "no observation",
                 spec->mask_paths[k], spec->image_paths[k]);
  if (s == CF_OK && d->exposure_status != CF_OK) {
    *err = d->exposure_err;
    s = d->exposure_status;
  }
  if (s != CF_OK) return s;
  capture->raw_exposures[k] = d->exposure;
  cf_capture_image *image = &capture->images[k];
  image->exposure = d->exposure;
  image->jpeg = d->jpeg;
  if (d->jpeg) set_jpeg_coding(capture, k, d);
  image->sphere_pixels = d->added.sphere_pixels;
  image->observations = d->added.observations;
  image->clipped = d->added.clipped;
  return CF_OK;
}

/* ---- every header before any pixel ---- */

typedef struct file_id {
  dev_t dev;
  ino_t ino;
  size_t image;
} file_id;

static int compare_ids(const void *a, const void *b) {
  const file_id *x = a, *y = b;
  if (x->dev != y->dev) return x->dev < y->dev ? -1 : 1;
  if (x->ino != y->ino) return x->ino < y->ino ? -1 : 1;
  return x->image < y->image ? -1 : x->image > y->image;
}

/* One file listed twice (by name, or through another path to it) would
 * count twice: double weight in the fit, and observations taken as
 * independent that are not, so an uncertainty too small. A measurement
 * should not be quietly biased, so it is an error, not a warning. Files
 * that cannot be examined are left to the reading that follows. */
static cf_status check_duplicates(const cf_capture *capture, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  size_t n = spec->num_images, found = 0;
  file_id *ids = malloc((n ? n : 1) * sizeof *ids);
  if (!ids) return cf_error_set(err, CF_ENOMEM, "out of memory for %zu images", n);
  for (size_t k = 0; k < n; ++k) {
    struct stat st;
    if (stat(spec->image_paths[k], &st) != 0) continue;
    ids[found].dev = st.st_dev, ids[found].ino = st.st_ino, ids[found].image = k;
    ++found;
  }
  qsort(ids, found, sizeof *ids, compare_ids);
  cf_status s = CF_OK;
  for (size_t i = 1; i < found && s == CF_OK; ++i)
    if (ids[i].dev == ids[i - 1].dev && ids[i].ino == ids[i - 1].ino)
      s = cf_error_set(err, CF_EINVAL,
                       "%s: images %zu (%s) and %zu (%s) are the same file; an image listed "
                       "twice would count twice in the fit (double weight, an uncertainty too "
                       "small)",
                       spec->path, ids[i - 1].image + 1, spec->image_names[ids[i - 1].image],
                       ids[i].image + 1, spec->image_names[ids[i].image]);
  free(ids);
  return s;
}

/* The kinds of samples among the images, for the warning about a mix. */
enum { SAMPLE_8, SAMPLE_16, SAMPLE_OTHER_INTEGER, SAMPLE_FLOAT, SAMPLE_KINDS };
static const char *const sample_kind_names[SAMPLE_KINDS] = {"8-bit", "16-bit", "other integer",
                                                            "float"};

static int sample_kind(const cf_image_info *info) {
  if (info->is_float) return SAMPLE_FLOAT;
  return info->bits_per_sample == 8    ? SAMPLE_8
         : info->bits_per_sample == 16 ? SAMPLE_16
                                       : SAMPLE_OTHER_INTEGER;
}

/* A warning when the images do not all store the same kind of sample: an
 * 8-bit image among 16-bit ones is 256 times more coarsely quantised and
 * has likely been through another pipeline (a tone curve). */
static void warn_mixed_samples(cf_capture *capture, const size_t counts[SAMPLE_KINDS],
                               const size_t first[SAMPLE_KINDS]) {
  int kinds = 0;
  for (int i = 0; i < SAMPLE_KINDS; ++i) kinds += counts[i] > 0;
  if (kinds < 2) return;
  char list[CF_ERROR_MESSAGE_SIZE] = "";
  size_t used = 0;
  for (int i = 0; i < SAMPLE_KINDS && used < sizeof list; ++i)
    if (counts[i])
      used += (size_t)snprintf(list + used, sizeof list - used, "%s%zu %s (%s%s)", used ? ", " : "",
                               counts[i], sample_kind_names[i], counts[i] > 1 ? "the first " : "",
                               capture->spec.image_names[first[i]]);
  capture_warn(capture,
               "the images mix sample types: %s; their quantisation and likely their processing "
               "differ",
               list);
}

/* Image k's header against its camera (capture_check_size, which records
 * its size), the normal map's header and its mask's header (or the shared
 * mask's). */
static cf_status check_header(cf_capture *capture, size_t k, const cf_image_header *mask_shared,
                              cf_image_header *h, unsigned long long *bytes, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  cf_status s = cf_image_read_header(spec->image_paths[k], h, err);
  if (s != CF_OK) return s;
  *bytes += cf_image_header_bytes(h);
  cf_image as_declared = {h->width, h->height, h->channels, NULL};
  if ((s = cf_image_header_refusal(capture_check_size(capture, k, &as_declared, err), err)) != CF_OK) return s;
  const cf_image *map = &capture->normal_map; /* its header's size (map_headers) */
  if (spec->normal_map && (map->width != h->width || map->height != h->height))
    return cf_image_header_refusal(
        cf_error_set(err, CF_EINVAL, "%s: the normal map is %d x %d pixels but %s is %d x %d",
                     spec->normal_map, map->width, map->height, spec->image_paths[k], h->width,
                     h->height),
        err);
  if (!spec->mask_paths) return CF_OK;
  cf_image_header own;
  const cf_image_header *mask = mask_shared;
  if (!mask) {
    if ((s = cf_image_read_header(spec->mask_paths[k], &own, err)) != CF_OK) return s;
    *bytes += cf_image_header_bytes(&own);
    mask = &own;
  }
  if (mask->width == h->width && mask->height == h->height) return CF_OK;
  return cf_image_header_refusal(
      cf_error_set(err, CF_EINVAL, "%s: the mask is %d x %d pixels but %s is %d x %d",
                   spec->mask_paths[k], mask->width, mask->height, spec->image_paths[k], h->width,
                   h->height),
      err);
}

/* CF_ERANGE when the bytes counted so far, up to `what` (a phrase naming
 * the files, the last one's size), pass the cap. */
static cf_status check_cap(const cf_capture *capture, unsigned long long bytes,
                           unsigned long long cap, const char *what, cf_error *err) {
  if (bytes <= cap) return CF_OK;
  return cf_error_set(err, CF_ERANGE,
                      "%s: %s decode to %.3g GB of 32-bit floats, more than the cap of %.3g GB on "
                      "a capture's image data (checked from the headers; raise it with clayfit's "
                      "--max-image-memory GB)",
                      capture->spec.path, what, (double)bytes / 1e9, (double)cap / 1e9);
}

/* The maps the capture names, before its photos: the normal map (its
 * header's size kept in capture->normal_map, pixels NULL, for the photos'
 * headers and its decoding to hold to) and each environment map, their
 * decoded bytes counted against the cap like the photos'. *maps: 1 when
 * there is one. */
static cf_status map_headers(cf_capture *capture, unsigned long long cap,
                             unsigned long long *bytes, int *maps, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  char what[CF_ERROR_MESSAGE_SIZE];
  cf_image_header h;
  cf_status s = CF_OK;
  *maps = 0;
  if (spec->normal_map) {
    *maps = 1;
    s = cf_image_read_header(spec->normal_map, &h, err);
    if (s == CF_OK) {
      *bytes += cf_image_header_bytes(&h);
      capture->normal_map.width = h.width, capture->normal_map.height = h.height;
      snprintf(what, sizeof what, "the normal map %s (%d x %d x %d)", spec->normal_map, h.width,
               h.height, h.channels);
      s = check_cap(capture, *bytes, cap, what, err);
    }
  }
  for (size_t i = 0; s == CF_OK && i < spec->num_lights; ++i) {
    const char *file = spec->lights[i].file;
    if (spec->lights[i].kind != CF_LIGHT_SPEC_ENVIRONMENT) continue;
    *maps = 1;
    if ((s = cf_image_read_header(file, &h, err)) != CF_OK) break;
    *bytes += cf_image_header_bytes(&h);
    snprintf(what, sizeof what, "the maps up to the environment map %s (%d x %d x %d)", file,
             h.width, h.height, h.channels);
    s = check_cap(capture, *bytes, cap, what, err);
  }
  return s;
}

/* 1 when every image has the same mask file (DiLiGenT's): decoded once. */
static int shares_one_mask(const cf_capture *capture) {
  const char *const *masks = (const char *const *)capture->spec.mask_paths;
  const size_t n = capture->spec.num_images;
  int one = masks && n > 1;
  for (size_t k = 1; one && k < n; ++k) one = strcmp(masks[k], masks[0]) == 0;
  return one;
}

/* Every map's, image's and mask's header, before any pixel is decoded: a
 * small compressed file may declare gigabytes (a 1.9 MB PNG declaring
 * 26000 x 26000 took 29 s and 10 GB to decode before its size was
 * refused). Also the total against the cap, duplicates, and a mix of
 * sample types (a warning). */
cf_status capture_read_headers(cf_capture *capture, const cf_capture_options *options,
                               cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  cf_status s = check_duplicates(capture, err);
  unsigned long long cap =
      options && options->max_image_bytes ? options->max_image_bytes : CF_CAPTURE_MAX_IMAGE_BYTES;
  unsigned long long bytes = 0;
  int maps = 0;
  if (s == CF_OK) s = map_headers(capture, cap, &bytes, &maps, err);
  const int one_mask = shares_one_mask(capture);
  cf_image_header shared;
  if (s == CF_OK && one_mask) {
    s = cf_image_read_header(spec->mask_paths[0], &shared, err);
    bytes += cf_image_header_bytes(&shared);
  }
  size_t counts[SAMPLE_KINDS] = {0}, first[SAMPLE_KINDS] = {0};
  for (size_t k = 0; s == CF_OK && k < spec->num_images; ++k) {
    cf_image_header h;
    s = check_header(capture, k, one_mask ? &shared : NULL, &h, &bytes, err);
    if (s != CF_OK) break;
    char what[CF_ERROR_MESSAGE_SIZE];
    snprintf(what, sizeof what,
             "%sthe images up to %s (%zu of %zu; %d x %d x %d the last) and their masks",
             maps ? "the maps and " : "", spec->image_names[k], k + 1, spec->num_images, h.width,
             h.height, h.channels);
    s = check_cap(capture, bytes, cap, what, err);
    if (s == CF_OK && counts[sample_kind(&h.info)]++ == 0) first[sample_kind(&h.info)] = k;
  }
  if (s == CF_OK) warn_mixed_samples(capture, counts, first);
  return s;
}

/* Room for every image's observations: the sum of their bounds
 * (capture_surface_bounds, from the headers' sizes); each image's bound
 * and the largest. */
static cf_status make_room(read_images *r, cf_error *err) {
  cf_capture *capture = r->capture;
  size_t total = 0;
  for (size_t k = 0; k < r->count; ++k) {
    int b[4];
    capture_surface_bounds(capture, k, capture->images[k].width, capture->images[k].height, b);
    r->slots[k].bound = (size_t)(b[2] - b[0]) * (size_t)(b[3] - b[1]);
    total += r->slots[k].bound;
    r->most = r->slots[k].bound > r->most ? r->slots[k].bound : r->most;
  }
  return capture_allocate_observations(&capture->obs, total, err);
}

/* The mask every image shares, decoded once. */
static void read_shared_mask(read_images *r) {
  cf_capture *capture = r->capture;
  const char *path = capture->spec.mask_paths[0];
  r->shared_status = cf_image_read_sized(path, capture->images[0].width,
                                         capture->images[0].height, &r->shared_mask, NULL,
                                         &r->shared_err);
  if (r->shared_status == CF_OK && mask_is_empty(&r->shared_mask))
    capture_warn(capture,
                 "%s: no pixel of this mask is usable (all are 0.5 or less), so no "
                 "image adds an observation",
                 path);
}

cf_status capture_read_images(cf_capture *capture, const cf_capture_options *options,
                              cf_error *err) {
  size_t n = capture->spec.num_images;
  read_images r;
  memset(&r, 0, sizeof r);
  r.capture = capture;
  r.count = r.first_failed = n;
  r.options = options;
  r.slots = calloc(n ? n : 1, sizeof *r.slots);
  if (!r.slots) return cf_error_set(err, CF_ENOMEM, "out of memory for %zu images", n);
  cf_status s = make_room(&r, err);
  if (s == CF_OK) {
    pthread_mutex_init(&r.lock, NULL);
    pthread_cond_init(&r.changed, NULL);
    r.one_mask = shares_one_mask(capture);
    if (r.one_mask) read_shared_mask(&r);
    const int parts = n < WORKERS ? (int)n : WORKERS;
    if (n > 0) cf_parallel_for(parts, parts, read_part, &r);
    pthread_mutex_destroy(&r.lock);
    pthread_cond_destroy(&r.changed);
    for (size_t k = 0; s == CF_OK && k < n; ++k) s = account(capture, k, &r.slots[k], err);
    if (s == CF_OK) capture_shrink_observations(&capture->obs);
  }
  free(r.slots);
  cf_image_free(&r.shared_mask);
  if (s == CF_OK && options && options->progress)
    options->progress(options->progress_user, "reading images", n, n);
  return s;
}
