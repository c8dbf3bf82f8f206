/* The one thread pool (src/core/include/core/parallel.h): every i called exactly once
 * for counts and thread counts around the edges (0 items, more threads
 * than items, more than the pool's cap), i = 0 on the calling thread, the
 * calls in order on one thread, a pool inside a pool, and cf_part_range's
 * parts tiling a range. */
#define _POSIX_C_SOURCE 200809L /* pthread_self */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "core/parallel.h"
#include "support/check.h"

CHECK_MAIN_STATE;

typedef struct calls {
  atomic_int *times; /* per i */
  atomic_int order;  /* the calls so far */
  int *seen_at;      /* per i: its place among the calls */
  int nested;        /* each call runs a pool of this many items (0: none) */
  atomic_int nested_calls;
  pthread_t caller, first; /* the calling thread; the one that ran i = 0 */
} calls;

static void count_nested(void *user, int i) {
  (void)i;
  atomic_fetch_add(&((calls *)user)->nested_calls, 1);
}

static void record(void *user, int i) {
  calls *c = user;
  atomic_fetch_add(&c->times[i], 1);
  c->seen_at[i] = atomic_fetch_add(&c->order, 1);
  if (i == 0) c->first = pthread_self();
  if (c->nested) cf_parallel_for(c->nested, 2, count_nested, c);
}

static void check_once(int count, int threads, int nested) {
  calls c = {calloc((size_t)count + 1, sizeof(atomic_int)),
             0,
             calloc((size_t)count + 1, sizeof(int)),
             nested,
             0,
             pthread_self(),
             pthread_self()};
  for (int i = 0; i < count; ++i) atomic_init(&c.times[i], 0);
  cf_parallel_for(count, threads, record, &c);
  int wrong = 0;
  for (int i = 0; i < count; ++i) wrong += atomic_load(&c.times[i]) != 1;
  CHECK(wrong == 0, "count %d, threads %d: %d items not called exactly once", count, threads,
        wrong);
  CHECK(atomic_load(&c.order) == count, "count %d, threads %d: %d calls", count, threads,
        atomic_load(&c.order));
  CHECK(atomic_load(&c.nested_calls) == count * nested, "count %d, threads %d: %d nested calls",
        count, threads, atomic_load(&c.nested_calls));
  CHECK(count == 0 || pthread_equal(c.first, c.caller), "count %d, threads %d: 0 on another thread",
        count, threads);
  if (threads <= 1) { /* on this thread, in order */
    int out_of_order = 0;
    for (int i = 0; i < count; ++i) out_of_order += c.seen_at[i] != i;
    CHECK(out_of_order == 0, "count %d on one thread: %d calls out of order", count, out_of_order);
  }
  free(c.times);
  free(c.seen_at);
}

static void check_parts(size_t count, int parts) {
  size_t expect = 0, smallest = (size_t)-1, largest = 0;
  int gaps = 0;
  for (int part = 0; part < parts; ++part) {
    size_t begin, end;
    cf_part_range(count, parts, part, &begin, &end);
    gaps += begin != expect || end < begin;
    expect = end;
    if (end - begin < smallest) smallest = end - begin;
    if (end - begin > largest) largest = end - begin;
  }
  CHECK(gaps == 0 && expect == count, "%zu items in %d parts: not tiled", count, parts);
  CHECK(largest - smallest <= 1, "%zu items in %d parts: sizes %zu..%zu", count, parts, smallest,
        largest);
}

int main(void) {
  const int counts[] = {0, 1, 2, 3, 17, 1000};
  const int threads[] = {-1, 0, 1, 2, 3, 16, 40};
  for (size_t a = 0; a < sizeof counts / sizeof *counts; ++a)
    for (size_t b = 0; b < sizeof threads / sizeof *threads; ++b)
      check_once(counts[a], threads[b], 0);
  check_once(50, 2, 7);
  check_once(50, 1, 3);
  for (size_t count = 0; count < 40; ++count)
    for (int parts = 1; parts <= 9; ++parts) check_parts(count, parts);
  return check_finish("test_parallel");
}
