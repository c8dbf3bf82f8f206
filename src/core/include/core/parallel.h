/* The one thread pool: independent pieces of work side by side (the
 * solver's passes over the residual blocks, the model ladder's
 * candidates, parts of a range of observations, a synthetic capture's
 * images and rows, a capture's image decoding): `count` calls
 * work(user, i), on up to `threads` threads, each i exactly once, handed
 * out in increasing i, i = 0 on this thread; returns when all are done.
 * Each call must touch only what is its own (results go to slot i), or
 * lock what it shares. With threads <= 1, or when no thread can be
 * started, the calls run here in order. An interface of core
 * to the layers above (src/core/include), never a public header. */
#ifndef CLAYFIT_CORE_PARALLEL_H
#define CLAYFIT_CORE_PARALLEL_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

void cf_parallel_for(int count, int threads, void (*work)(void *user, int i), void *user);

/* The items [*begin, *end) of part `part` of `parts` over `count` items in
 * order (for a cf_parallel_for over parts of one range). */
void cf_part_range(size_t count, int parts, int part, size_t *begin, size_t *end);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_CORE_PARALLEL_H */
