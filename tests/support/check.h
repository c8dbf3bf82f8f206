/* Minimal assertions for clayfit's ctest executables: every CHECK counts,
 * the first failures are printed, and check_finish() turns the count into
 * the exit status. */
#ifndef CLAYFIT_TEST_CHECK_H
#define CLAYFIT_TEST_CHECK_H

#include <stdio.h>

typedef struct check_state {
  long checks, failures;
} check_state;

extern check_state check_global;

#define CHECK(cond, ...)                                                         \
  do {                                                                           \
    ++check_global.checks;                                                       \
    if (!(cond)) {                                                               \
      if (++check_global.failures <= 20) {                                       \
        fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond); \
        fprintf(stderr, __VA_ARGS__);                                            \
        fputc('\n', stderr);                                                     \
      }                                                                          \
    }                                                                            \
  } while (0)

/* Print the summary; return the process exit status (0 = all passed). */
static inline int check_finish(const char *name) {
  printf("%s: %ld checks, %ld failed\n", name, check_global.checks, check_global.failures);
  return check_global.failures ? 1 : 0;
}

#define CHECK_MAIN_STATE check_state check_global = {0, 0}

/* The exit status that tells ctest a test was skipped (SKIP_RETURN_CODE). */
#define CHECK_SKIPPED 77

#endif /* CLAYFIT_TEST_CHECK_H */
