/* Every image's pixels into observations (capture_internal.h): decoding a
 * file (OpenImageIO, the finite check, its mask) is the slow part and
 * needs nothing from the others, so READERS threads decode ahead, at most
 * AHEAD images beyond the one being added, while this thread adds each
 * image's observations in order (they append to the capture's arrays, and
 * their order is the images'). The first error in image order is the one
 * reported, as if the images were read one by one. One mask file for
 * every image (DiLiGenT's) is decoded once. */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"

enum { READERS = 2, AHEAD = 4 };

typedef struct decoded {
  cf_image image, mask;
  cf_image_info info;
  cf_status status;
  cf_error err;
  int ready;
} decoded;

typedef struct read_ahead {
  cf_capture *capture;
  decoded *slots; /* one per image */
  /* one mask for every image: decoded once (its status and error stand
   * for each image's) */
  int one_mask;
  cf_image shared_mask;
  cf_status shared_status;
  cf_error shared_err;
  size_t count, next, added; /* images; the next to decode; those added */
  int stop;
  pthread_mutex_t lock;
  pthread_cond_t changed;
} read_ahead;

static cf_status check_mask(const cf_capture *capture, size_t k, const cf_image *image,
                            const cf_image *mask, cf_error *err) {
  if (mask->width == image->width && mask->height == image->height) return CF_OK;
  return cf_error_set(err, CF_EINVAL, "%s: the mask is %d x %d pixels but %s is %d x %d",
                      capture->spec.mask_paths[k], mask->width, mask->height,
                      capture->spec.image_paths[k], image->width, image->height);
}

/* Image k's own mask, or the one every image shares. */
static const cf_image *mask_of(const read_ahead *r, const decoded *d) {
  if (!r->capture->spec.mask_paths) return NULL;
  return r->one_mask ? &r->shared_mask : &d->mask;
}

/* Image k's pixels and mask (reads only the capture's file names and the
 * shared mask). */
static void decode(const read_ahead *r, size_t k, decoded *d) {
  const cf_capture *capture = r->capture;
  const cf_capture_spec *spec = &capture->spec;
  d->status = cf_image_read(spec->image_paths[k], &d->image, &d->info, &d->err);
  if (d->status == CF_OK && d->info.is_float) /* integer samples are finite */
    d->status = cf_image_check_finite(&d->image, spec->image_paths[k], &d->err);
  if (d->status != CF_OK || !spec->mask_paths) return;
  if (!r->one_mask) {
    d->status = cf_image_read(spec->mask_paths[k], &d->mask, NULL, &d->err);
  } else if (r->shared_status != CF_OK) {
    d->status = r->shared_status;
    d->err = r->shared_err;
  }
  if (d->status == CF_OK) d->status = check_mask(capture, k, &d->image, mask_of(r, d), &d->err);
}

static void *reader(void *arg) {
  read_ahead *r = arg;
  pthread_mutex_lock(&r->lock);
  for (;;) {
    while (!r->stop && r->next < r->count && r->next >= r->added + AHEAD)
      pthread_cond_wait(&r->changed, &r->lock);
    if (r->stop || r->next >= r->count) break;
    size_t k = r->next++;
    pthread_mutex_unlock(&r->lock);
    decode(r, k, &r->slots[k]);
    pthread_mutex_lock(&r->lock);
    r->slots[k].ready = 1;
    pthread_cond_broadcast(&r->changed);
  }
  pthread_mutex_unlock(&r->lock);
  return NULL;
}

/* Image k's observations from its decoded pixels. */
static cf_status add(cf_capture *capture, size_t k, decoded *d, const cf_image *mask,
                     cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  if (d->status != CF_OK) {
    *err = d->err;
    return d->status;
  }
  cf_status s = capture_check_size(capture, k, &d->image, err);
  if (s == CF_OK && capture->normal_map.pixels &&
      (capture->normal_map.width != d->image.width ||
       capture->normal_map.height != d->image.height))
    s = cf_error_set(err, CF_EINVAL, "%s: the normal map is %d x %d pixels but %s is %d x %d",
                     spec->normal_map, capture->normal_map.width, capture->normal_map.height,
                     spec->image_paths[k], d->image.width, d->image.height);
  double exposure = 1.0;
  if (s == CF_OK) s = capture_raw_exposure(capture, k, &d->info, &exposure, err);
  if (s == CF_OK) {
    capture->raw_exposures[k] = exposure;
    capture->images[k].exposure = exposure;
    cf_decode decoding = capture_image_decode(capture, &d->info, exposure);
    s = capture_add_observations(capture, k, &d->image, mask, &decoding, err);
  }
  return s;
}

cf_status capture_read_images(cf_capture *capture, const cf_capture_options *options,
                              cf_error *err) {
  size_t n = capture->spec.num_images;
  read_ahead r;
  memset(&r, 0, sizeof r);
  r.capture = capture;
  r.slots = calloc(n ? n : 1, sizeof(decoded));
  r.count = n;
  pthread_mutex_init(&r.lock, NULL);
  pthread_cond_init(&r.changed, NULL);
  if (!r.slots) {
    pthread_mutex_destroy(&r.lock);
    pthread_cond_destroy(&r.changed);
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu images", n);
  }
  const char *const *masks = (const char *const *)capture->spec.mask_paths;
  r.one_mask = masks && n > 1;
  for (size_t k = 1; r.one_mask && k < n; ++k) r.one_mask = strcmp(masks[k], masks[0]) == 0;
  if (r.one_mask) r.shared_status = cf_image_read(masks[0], &r.shared_mask, NULL, &r.shared_err);
  pthread_t threads[READERS];
  int started = 0;
  for (; started < READERS && (size_t)started < n; ++started)
    if (pthread_create(&threads[started], NULL, reader, &r) != 0) break;
  cf_status s = CF_OK;
  if (started == 0 && n > 0) s = cf_error_set(err, CF_EIO, "cannot start a thread to read images");
  for (size_t k = 0; s == CF_OK && k < n; ++k) {
    if (options && options->progress)
      options->progress(options->progress_user, "reading images", k, n);
    pthread_mutex_lock(&r.lock);
    while (!r.slots[k].ready) pthread_cond_wait(&r.changed, &r.lock);
    pthread_mutex_unlock(&r.lock);
    s = add(capture, k, &r.slots[k], mask_of(&r, &r.slots[k]), err);
    cf_image_free(&r.slots[k].image);
    cf_image_free(&r.slots[k].mask);
    pthread_mutex_lock(&r.lock);
    r.added = k + 1;
    pthread_cond_broadcast(&r.changed);
    pthread_mutex_unlock(&r.lock);
  }
  pthread_mutex_lock(&r.lock); /* on an error, the readers stop at their next image */
  r.stop = 1;
  pthread_cond_broadcast(&r.changed);
  pthread_mutex_unlock(&r.lock);
  for (int t = 0; t < started; ++t) pthread_join(threads[t], NULL);
  for (size_t k = 0; k < n; ++k) { /* what was decoded ahead of an error */
    cf_image_free(&r.slots[k].image);
    cf_image_free(&r.slots[k].mask);
  }
  free(r.slots);
  cf_image_free(&r.shared_mask);
  pthread_mutex_destroy(&r.lock);
  pthread_cond_destroy(&r.changed);
  if (s == CF_OK && options && options->progress)
    options->progress(options->progress_user, "reading images", n, n);
  return s;
}
