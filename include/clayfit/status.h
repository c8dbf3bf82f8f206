/* clayfit: status codes and the caller-owned error record.
 *
 * Every fallible clayfit function returns a cf_status and, when the caller
 * passes a cf_error, fills it with a message that says what is wrong and
 * where (file, line, column, field). There is no global error state.
 *
 * One table, CF_STATUS_MAP, generates the enum, the names and the generic
 * messages (after libuv's UV_ERRNO_MAP). */
#ifndef CLAYFIT_STATUS_H
#define CLAYFIT_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

/* X(NAME, code, generic message) */
/* clang-format off */
#define CF_STATUS_MAP(X)                                                 \
  X(OK, 0, "success")                                                    \
  X(EINVAL, -1, "invalid argument")                                      \
  X(ERANGE, -2, "value out of range")                                    \
  X(ENOMEM, -3, "out of memory")                                         \
  X(EIO, -4, "input/output error")                                       \
  X(EPARSE, -5, "malformed input")                                       \
  X(ENOTFOUND, -6, "not found")                                          \
  X(EUNSUPPORTED, -7, "not supported")                                   \
  X(ENUMERIC, -8, "numerical failure")

/* clang-format on */

typedef enum cf_status {
#define CF__STATUS_ENUM(name, code, msg) CF_##name = code,
  CF_STATUS_MAP(CF__STATUS_ENUM)
#undef CF__STATUS_ENUM
} cf_status;

/* Capacity of the message buffer of cf_error, terminating NUL included. */
#define CF_ERROR_MESSAGE_SIZE 1024

/* A caller-owned error record. Zero-initialise it (cf_error e = {0};) and
 * pass its address; on failure status is set and message holds a complete,
 * human-readable sentence including the context (for example
 * "capture.json:12:7: images[3].path: expected a string"). */
typedef struct cf_error {
  cf_status status;
  char message[CF_ERROR_MESSAGE_SIZE];
} cf_error;

/* "EINVAL" for CF_EINVAL; "UNKNOWN" for a code outside the table. */
const char *cf_status_name(cf_status status);

/* The generic message for a status ("invalid argument"). */
const char *cf_status_message(cf_status status);

/* Fill err (if not NULL) with status and a printf-style message; returns
 * status so that callers can write `return cf_error_set(err, ...);`.
 * A message longer than the buffer is truncated and ends in "...". */
cf_status cf_error_set(cf_error *err, cf_status status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Put context in front of an existing message: "<prefix>: <old message>". */
void cf_error_prefix(cf_error *err, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_STATUS_H */
