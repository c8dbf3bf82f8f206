/* Escaping untrusted text for each output syntax (text_escape.h). */
#include "core/text_escape.h"

#include <stdlib.h>
#include <string.h>

#define REPLACEMENT "\xef\xbf\xbd" /* U+FFFD in UTF-8 */

/* ---- the output: a buffer, snprintf-like and cut only between whole
 * escapes; or a file ---- */

typedef struct sink {
  char *out;
  size_t size, length, written;
  int cut;
  FILE *file; /* instead of out */
  int failed; /* a write to file failed */
} sink;

static void put(sink *s, const char *text, size_t n) {
  if (s->file) {
    if (fwrite(text, 1, n, s->file) != n) s->failed = 1;
  } else if (!s->cut && s->written + n < s->size) {
    memcpy(s->out + s->written, text, n);
    s->written += n;
  } else {
    s->cut = 1;
  }
  s->length += n;
}

static void put_text(sink *s, const char *text) {
  put(s, text, strlen(text));
}

static void put_hex(sink *s, const char *prefix, unsigned value, int digits) {
  static const char hex[] = "0123456789abcdef";
  char text[16];
  size_t n = strlen(prefix);
  memcpy(text, prefix, n);
  for (int i = digits - 1; i >= 0; --i) text[n++] = hex[(value >> (4 * i)) & 0xf];
  put(s, text, n);
}

/* ---- the input: one character (or one byte of invalid UTF-8) at a time ---- */

typedef struct unit {
  const unsigned char *at; /* its bytes */
  int length;              /* 1 for a byte of invalid UTF-8 */
  unsigned cp;             /* the code point, when valid */
  int valid, first;
} unit;

/* The length (1 to 4) of the valid UTF-8 sequence at s, and its code point;
 * 0 if invalid (overlong, a surrogate, above U+10FFFF, cut short). */
static int utf8_decode(const unsigned char *s, unsigned *cp) {
  unsigned c = s[0], min;
  int n;
  if (c < 0x80) {
    *cp = c;
    return 1;
  }
  if (c >= 0xc2 && c <= 0xdf)
    n = 2, *cp = c & 0x1f, min = 0x80;
  else if ((c & 0xf0) == 0xe0)
    n = 3, *cp = c & 0x0f, min = 0x800;
  else if (c >= 0xf0 && c <= 0xf4)
    n = 4, *cp = c & 0x07, min = 0x10000;
  else
    return 0;
  for (int i = 1; i < n; ++i) { /* stops at the NUL: it is not a continuation byte */
    if ((s[i] & 0xc0) != 0x80) return 0;
    *cp = (*cp << 6) | (s[i] & 0x3f);
  }
  if (*cp < min || *cp > 0x10ffff || (*cp >= 0xd800 && *cp <= 0xdfff)) return 0;
  return n;
}

static int is_control(unsigned cp) {
  return cp < 0x20 || (cp >= 0x7f && cp <= 0x9f);
}

/* The unsafe characters of text_escape.h. */
static int is_unsafe(unsigned cp) {
  return is_control(cp) || cp == 0x2028 || cp == 0x2029 || (cp >= 0x202a && cp <= 0x202e) ||
         (cp >= 0x2066 && cp <= 0x2069) || cp == 0xfeff || cp == 0xfffe || cp == 0xffff;
}

typedef void (*unit_writer)(sink *s, const unit *u);

static void escape(sink *s, const char *text, const char *open, const char *close,
                   unit_writer write) {
  put_text(s, open);
  const unsigned char *p = (const unsigned char *)(text ? text : "");
  for (int first = 1; *p; first = 0) {
    unit u = {p, 1, 0, 0, first};
    int n = utf8_decode(p, &u.cp);
    if (n > 0) u.length = n, u.valid = 1;
    write(s, &u);
    p += u.length;
  }
  put_text(s, close);
}

/* ---- the syntaxes ---- */

static void put_bytes_hex(sink *s, const unit *u) {
  for (int i = 0; i < u->length; ++i) put_hex(s, "\\x", u->at[i], 2);
}

/* What the two comment syntaxes share: backslash escapes, one line. */
static int comment_common(sink *s, const unit *u) {
  if (!u->valid || is_unsafe(u->cp)) {
    if (u->valid && u->cp == '\n')
      put_text(s, "\\n");
    else if (u->valid && u->cp == '\r')
      put_text(s, "\\r");
    else if (u->valid && u->cp == '\t')
      put_text(s, "\\t");
    else
      put_bytes_hex(s, u);
    return 1;
  }
  if (u->cp == '\\') {
    put_text(s, "\\\\");
    return 1;
  }
  return 0;
}

static void python_comment_unit(sink *s, const unit *u) {
  if (!comment_common(s, u)) put(s, (const char *)u->at, (size_t)u->length);
}

static void xml_comment_unit(sink *s, const unit *u) {
  if (comment_common(s, u)) return;
  unsigned char next = u->at[1];
  if (u->cp == '-' && (u->first || next == '-' || next == '\0'))
    put_text(s, "\\x2d");
  else
    put(s, (const char *)u->at, (size_t)u->length);
}

static void python_string_unit(sink *s, const unit *u) {
  unsigned cp = u->cp;
  if (!u->valid)
    put_hex(s, "\\udc", u->at[0], 2);
  else if (cp == '"')
    put_text(s, "\\\"");
  else if (cp == '\\')
    put_text(s, "\\\\");
  else if (cp == '\n')
    put_text(s, "\\n");
  else if (cp == '\r')
    put_text(s, "\\r");
  else if (cp == '\t')
    put_text(s, "\\t");
  else if (cp >= 0x20 && cp < 0x7f)
    put(s, (const char *)u->at, 1);
  else if (cp < 0x100)
    put_hex(s, "\\x", cp, 2);
  else if (cp < 0x10000)
    put_hex(s, "\\u", cp, 4);
  else
    put_hex(s, "\\U", cp, 8);
}

static void xml_unit(sink *s, const unit *u) {
  unsigned cp = u->cp;
  if (!u->valid) {
    put_text(s, REPLACEMENT);
    return;
  }
  static const struct {
    unsigned cp;
    const char *entity;
  } entities[] = {{'&', "&amp;"},  {'<', "&lt;"},  {'>', "&gt;"},   {'"', "&quot;"},
                  {'\'', "&#39;"}, {'\t', "&#9;"}, {'\n', "&#10;"}, {'\r', "&#13;"}};
  for (size_t i = 0; i < sizeof entities / sizeof entities[0]; ++i)
    if (cp == entities[i].cp) {
      put_text(s, entities[i].entity);
      return;
    }
  if (is_control(cp) || cp == 0xfffe || cp == 0xffff) {
    put_text(s, REPLACEMENT); /* not an XML 1.0 character, or not one for HTML */
  } else if (is_unsafe(cp)) {
    put_hex(s, "&#x", cp, 4);
    put_text(s, ";");
  } else {
    put(s, (const char *)u->at, (size_t)u->length);
  }
}

static void utf8_unit(sink *s, const unit *u) {
  if (u->valid)
    put(s, (const char *)u->at, (size_t)u->length);
  else
    put_text(s, REPLACEMENT);
}

/* The syntaxes by their function, so that text_escape_fputs can stream. */
typedef struct syntax {
  text_escape_fn function;
  const char *open, *close;
  unit_writer write;
} syntax;

static const syntax syntaxes[] = {
    {text_escape_python_comment, "", "", python_comment_unit},
    {text_escape_python_string, "\"", "\"", python_string_unit},
    {text_escape_xml, "", "", xml_unit},
    {text_escape_html, "", "", xml_unit},
    {text_escape_xml_comment, "", "", xml_comment_unit},
    {text_escape_utf8, "", "", utf8_unit},
};

static size_t to_buffer(char *out, size_t size, const char *text, int which) {
  sink s = {out, size, 0, 0, 0, NULL, 0};
  escape(&s, text, syntaxes[which].open, syntaxes[which].close, syntaxes[which].write);
  if (size) out[s.written] = '\0';
  return s.length;
}

size_t text_escape_python_comment(char *out, size_t size, const char *text) {
  return to_buffer(out, size, text, 0);
}

size_t text_escape_python_string(char *out, size_t size, const char *text) {
  return to_buffer(out, size, text, 1);
}

size_t text_escape_xml(char *out, size_t size, const char *text) {
  return to_buffer(out, size, text, 2);
}

size_t text_escape_html(char *out, size_t size, const char *text) {
  return to_buffer(out, size, text, 3);
}

size_t text_escape_xml_comment(char *out, size_t size, const char *text) {
  return to_buffer(out, size, text, 4);
}

size_t text_escape_utf8(char *out, size_t size, const char *text) {
  return to_buffer(out, size, text, 5);
}

/* ---- conveniences ---- */

int text_is_utf8(const char *text) {
  unsigned cp;
  for (const unsigned char *p = (const unsigned char *)(text ? text : ""); *p;) {
    int n = utf8_decode(p, &cp);
    if (n == 0) return 0;
    p += n;
  }
  return 1;
}

char *text_escape_alloc(text_escape_fn escape_text, const char *text) {
  size_t length = escape_text(NULL, 0, text);
  char *out = malloc(length + 1);
  if (out) escape_text(out, length + 1, text);
  return out;
}

int text_escape_fputs(FILE *f, text_escape_fn escape_text, const char *text) {
  for (size_t i = 0; i < sizeof syntaxes / sizeof syntaxes[0]; ++i)
    if (syntaxes[i].function == escape_text) {
      sink s = {NULL, 0, 0, 0, 0, f, 0};
      escape(&s, text, syntaxes[i].open, syntaxes[i].close, syntaxes[i].write);
      return s.failed ? -1 : 0;
    }
  char *escaped = text_escape_alloc(escape_text, text); /* another function */
  int status = escaped && fputs(escaped, f) >= 0 ? 0 : -1;
  free(escaped);
  return status;
}
