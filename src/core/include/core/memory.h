/* Memory for the large arrays (observations, a fit's rows and pairs, a
 * report's predictions): malloc, with the kernel asked to back the array
 * with huge pages where it can (transparent huge pages in madvise mode).
 * The first touch of fresh pages is most of the kernel's time in loading,
 * fitting and reporting; 2 MiB at a time instead of 4 KiB (loading the
 * 96-image sphere: 3.2 s of CPU with them, 5.6 s without, 12·10³ page
 * faults against 260·10³; the demo's report 0.81× the CPU time). Free
 * with free(). */
#ifndef CLAYFIT_CORE_MEMORY_H
#define CLAYFIT_CORE_MEMORY_H

#include <stddef.h>

void *cf_malloc_large(size_t bytes);

#endif /* CLAYFIT_CORE_MEMORY_H */
