/* Untrusted text (a capture's name, a path, an image name) into an output
 * file: one escaping function per output syntax, used by every writer that
 * builds text with printf-like formatting (the exports, the report). JSON is
 * written by Jansson, which escapes; text_escape_utf8 makes a string valid
 * UTF-8 so that Jansson takes it. Internal to clayfit (src/). Pure C.
 *
 * Every function is used like snprintf: it writes the escaped `text` into
 * `out` (at most size - 1 bytes and a NUL; nothing if size is 0) and returns
 * the length of the whole escaped text. An output too short is cut before
 * the first escape that does not fit whole, so even a cut text is safe. A
 * NULL text is the empty text. Invalid UTF-8 never passes through as it is.
 *
 * "Unsafe" below: C0 controls (U+0000-U+001F), DEL and C1 controls
 * (U+007F-U+009F), the Unicode line and paragraph separators U+2028, U+2029,
 * the bidirectional controls U+202A-U+202E and U+2066-U+2069 (which can make
 * text read differently from what it is), U+FEFF, and the non-characters
 * U+FFFE, U+FFFF. */
#ifndef CLAYFIT_CORE_TEXT_ESCAPE_H
#define CLAYFIT_CORE_TEXT_ESCAPE_H

#include <stddef.h>
#include <stdio.h>

typedef size_t (*text_escape_fn)(char *out, size_t size, const char *text);

/* The text of a Python `#` comment, kept on one line and reversible:
 * `\` as `\\`, newline, CR and tab as `\n`, `\r`, `\t`, every byte of
 * another unsafe character or of invalid UTF-8 as `\xNN`. (The caller's
 * comment must not be on the first two lines of the file, where Python
 * reads `coding:` declarations.) */
size_t text_escape_python_comment(char *out, size_t size, const char *text);

/* A whole Python string literal, quotes included, in ASCII: printable
 * ASCII as it is but `"` and `\` (escaped), `\n`, `\r`, `\t`, other
 * characters as `\xNN`, `\uNNNN` or `\UNNNNNNNN`, a byte of invalid UTF-8 as
 * `\udcNN` (Python's surrogateescape: os.fsencode gives the byte back). */
size_t text_escape_python_string(char *out, size_t size, const char *text);

/* XML (and SVG) text and attribute values, in single or double quotes:
 * `&<>"'` as `&amp;` `&lt;` `&gt;` `&quot;` `&#39;`; tab, newline and CR as
 * character references (kept through attribute normalisation); the other
 * unsafe characters that XML 1.0 allows as `&#xNNNN;`; those it does not
 * allow (C0 controls, DEL, C1 controls, U+FFFE, U+FFFF) and invalid UTF-8
 * as U+FFFD. */
size_t text_escape_xml(char *out, size_t size, const char *text);

/* HTML text and attribute values (quoted): the rules of text_escape_xml,
 * which are valid HTML too (C1 controls must not be character references
 * there: browsers read &#x80;-&#x9F; as Windows-1252). Not for the inside of
 * <script> or <style>. */
size_t text_escape_html(char *out, size_t size, const char *text);

/* The text of an XML comment, reversible as text_escape_python_comment's,
 * and with no `--`, no leading and no trailing `-`: such a `-` is written
 * `\x2d`. */
size_t text_escape_xml_comment(char *out, size_t size, const char *text);

/* Valid UTF-8 for a JSON string written by Jansson (which escapes quotes,
 * backslashes and controls itself): each byte of invalid UTF-8 as U+FFFD,
 * the rest as it is. */
size_t text_escape_utf8(char *out, size_t size, const char *text);

/* 1 if text is valid UTF-8, which text_escape_utf8 leaves as it is. */
int text_is_utf8(const char *text);

/* The escaped text in a new buffer (free() it); NULL if out of memory. */
char *text_escape_alloc(text_escape_fn escape, const char *text);

/* Write the escaped text to f, a piece at a time (the functions above
 * allocate nothing): 0 on success, -1 if a write failed (ferror(f) says so
 * too). */
int text_escape_fputs(FILE *f, text_escape_fn escape, const char *text);

#endif /* CLAYFIT_CORE_TEXT_ESCAPE_H */
