/* Status names and messages from the single CF_STATUS_MAP table, and the
 * caller-owned error record. */
#include "clayfit/status.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

const char *cf_status_name(cf_status status) {
  switch (status) {
#define CF__STATUS_NAME(name, code, msg) \
  case CF_##name:                        \
    return #name;
    CF_STATUS_MAP(CF__STATUS_NAME)
#undef CF__STATUS_NAME
  }
  return "UNKNOWN";
}

const char *cf_status_message(cf_status status) {
  switch (status) {
#define CF__STATUS_MESSAGE(name, code, msg) \
  case CF_##name:                           \
    return msg;
    CF_STATUS_MAP(CF__STATUS_MESSAGE)
#undef CF__STATUS_MESSAGE
  }
  return "unknown status";
}

/* Mark a truncated message with a trailing ellipsis. */
static void mark_truncated(char *buffer, size_t size, int written) {
  if (written >= 0 && (size_t)written < size) return;
  memcpy(buffer + size - 4, "...", 4);
}

cf_status cf_error_set(cf_error *err, cf_status status, const char *format, ...) {
  if (!err) return status;
  err->status = status;
  va_list args;
  va_start(args, format);
  int written = vsnprintf(err->message, sizeof err->message, format, args);
  va_end(args);
  mark_truncated(err->message, sizeof err->message, written);
  return status;
}

void cf_error_prefix(cf_error *err, const char *format, ...) {
  if (!err) return;
  char prefix[CF_ERROR_MESSAGE_SIZE];
  va_list args;
  va_start(args, format);
  vsnprintf(prefix, sizeof prefix, format, args);
  va_end(args);
  char old[CF_ERROR_MESSAGE_SIZE];
  memcpy(old, err->message, sizeof old);
  int written = snprintf(err->message, sizeof err->message, "%s: %s", prefix, old);
  mark_truncated(err->message, sizeof err->message, written);
}
