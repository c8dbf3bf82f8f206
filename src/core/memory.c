/* Memory for the large arrays (memory.h). */
#define _DEFAULT_SOURCE /* madvise */
#include "core/memory.h"

#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

/* The whole pages inside [p, p + bytes) advised, when they span more than
 * one huge page (below that the advice cannot pay); only the advice, which
 * the kernel may ignore: nothing else depends on it. */
static void advise_huge(void *p, size_t bytes) {
#ifdef MADV_HUGEPAGE
  const uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE), huge = (uintptr_t)2 << 20;
  uintptr_t begin = ((uintptr_t)p + page - 1) / page * page, end = (uintptr_t)p + bytes;
  if (end > begin + huge) madvise((void *)begin, (end - begin) / page * page, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}

void *cf_malloc_large(size_t bytes) {
  void *p = malloc(bytes ? bytes : 1);
  if (p) advise_huge(p, bytes);
  return p;
}
