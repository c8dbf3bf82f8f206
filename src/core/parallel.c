/* The one thread pool (parallel.h). */
#define _POSIX_C_SOURCE 200809L /* pthreads */
#include "core/parallel.h"

#include <pthread.h>

/* a bound, not a tuning: the pool lives on the stack; more threads asked
 * (--threads takes up to 256) share the work among these 16, and no
 * machine measured here has more than 4 cores */
enum { MOST_THREADS = 16 };

typedef struct parallel_for {
  int count, next;
  void (*work)(void *user, int i);
  void *user;
  pthread_mutex_t lock;
} parallel_for;

static void *worker(void *arg) {
  parallel_for *f = arg;
  for (;;) {
    pthread_mutex_lock(&f->lock);
    int i = f->next < f->count ? f->next++ : -1;
    pthread_mutex_unlock(&f->lock);
    if (i < 0) return NULL;
    f->work(f->user, i);
  }
}

void cf_parallel_for(int count, int threads, void (*work)(void *user, int i), void *user) {
  if (count <= 0) return;
  parallel_for f = {count, 1, work, user, PTHREAD_MUTEX_INITIALIZER}; /* 0 is this thread's */
  if (threads > MOST_THREADS) threads = MOST_THREADS;
  if (threads > count) threads = count;
  pthread_t pool[MOST_THREADS];
  int started = 0;
  for (; started + 1 < threads; ++started) /* this thread is the last worker */
    if (pthread_create(&pool[started], NULL, worker, &f) != 0) break;
  work(user, 0);
  worker(&f);
  for (int t = 0; t < started; ++t) pthread_join(pool[t], NULL);
  pthread_mutex_destroy(&f.lock);
}

void cf_part_range(size_t count, int parts, int part, size_t *begin, size_t *end) {
  *begin = count * (size_t)part / (size_t)parts;
  *end = count * ((size_t)part + 1) / (size_t)parts;
}
