/* The escaping of untrusted text for each output syntax (core/text_escape.h):
 *   - exact outputs for each kind of character, per syntax;
 *   - the empty and the NULL text; every control character; `--` runs and
 *     leading or trailing `-` in XML comments; invalid UTF-8 (a stray
 *     continuation byte, overlong, surrogate, above U+10FFFF, cut short);
 *   - every string of one and two bytes and many random ones: the output is
 *     valid UTF-8, has no character the syntax forbids, and the comment
 *     escapes give the input back;
 *   - a long text (alloc), and a short output buffer cut between whole
 *     escapes, with the full length returned as snprintf does. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/text_escape.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static void expect(text_escape_fn escape, const char *name, const char *in, const char *want) {
  char out[1024];
  size_t n = escape(out, sizeof out, in);
  CHECK(n == strlen(want) && strcmp(out, want) == 0, "%s(\"%s\") gave \"%s\" (%zu), not \"%s\"",
        name, in ? in : "(null)", out, n, want);
}

/* The length of the valid UTF-8 sequence at s, 0 if invalid: written apart
 * from the module's decoder, from RFC 3629's table. */
static int utf8_length(const unsigned char *s) {
  unsigned c = s[0];
  if (c < 0x80) return 1;
  int n = c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3 : c >= 0xf0 && c <= 0xf4 ? 4 : 0;
  if (!n) return 0;
  unsigned lo = 0x80, hi = 0xbf; /* the second byte's range */
  if (c == 0xe0) lo = 0xa0;
  if (c == 0xed) hi = 0x9f;
  if (c == 0xf0) lo = 0x90;
  if (c == 0xf4) hi = 0x8f;
  if (s[1] < lo || s[1] > hi) return 0;
  for (int i = 2; i < n; ++i)
    if ((s[i] & 0xc0) != 0x80) return 0;
  return n;
}

static int valid_utf8(const char *text) {
  for (const unsigned char *s = (const unsigned char *)text; *s;) {
    int n = utf8_length(s);
    if (!n) return 0;
    s += n;
  }
  return 1;
}

static int has_control_byte(const char *text) {
  for (const unsigned char *s = (const unsigned char *)text; *s; ++s)
    if (*s < 0x20 || *s == 0x7f) return 1;
  return 0;
}

/* The comment escapes back to bytes; -1 on an escape they never write. */
static int unescape_comment(const char *in, char *out) {
  size_t k = 0;
  for (const char *s = in; *s; ++s) {
    if (*s != '\\') {
      out[k++] = *s;
      continue;
    }
    char c = *++s;
    if (c == '\\' || c == 'n' || c == 'r' || c == 't') {
      out[k++] = c == 'n' ? '\n' : c == 'r' ? '\r' : c == 't' ? '\t' : '\\';
    } else if (c == 'x' && s[1] && s[2]) {
      char hex[3] = {s[1], s[2], 0};
      out[k++] = (char)strtol(hex, NULL, 16);
      s += 2;
    } else {
      return -1;
    }
  }
  out[k] = '\0';
  return 0;
}

/* What each output may hold, whatever the input. */
static void check_properties(const char *in, const char *label) {
  char out[256], back[256];
  text_escape_python_comment(out, sizeof out, in);
  CHECK(valid_utf8(out) && !has_control_byte(out), "python comment of %s", label);
  CHECK(unescape_comment(out, back) == 0 && strcmp(back, in) == 0,
        "python comment of %s does not give it back", label);

  text_escape_xml_comment(out, sizeof out, in);
  size_t n = strlen(out);
  CHECK(valid_utf8(out) && !has_control_byte(out), "xml comment of %s", label);
  CHECK(!strstr(out, "--") && (n == 0 || (out[0] != '-' && out[n - 1] != '-')),
        "xml comment of %s has a '--' or a '-' at an end: %s", label, out);
  CHECK(unescape_comment(out, back) == 0 && strcmp(back, in) == 0,
        "xml comment of %s does not give it back", label);

  text_escape_xml(out, sizeof out, in);
  CHECK(valid_utf8(out) && !has_control_byte(out) && !strpbrk(out, "<>\"'"), "xml text of %s: %s",
        label, out);
  for (const char *a = strchr(out, '&'); a; a = strchr(a + 1, '&'))
    CHECK(strncmp(a, "&amp;", 5) == 0 || strncmp(a, "&lt;", 4) == 0 || strncmp(a, "&gt;", 4) == 0 ||
              strncmp(a, "&quot;", 6) == 0 || strncmp(a, "&#", 2) == 0,
          "xml text of %s: a bare '&'", label);

  text_escape_python_string(out, sizeof out, in);
  n = strlen(out);
  int ascii = 1;
  for (size_t i = 0; i < n; ++i) ascii &= out[i] >= 0x20 && out[i] < 0x7f;
  CHECK(ascii && n >= 2 && out[0] == '"' && out[n - 1] == '"',
        "python string of %s is not one quoted ASCII literal: %s", label, out);
  for (size_t i = 1; i + 1 < n; ++i) { /* every inner quote is escaped */
    if (out[i] == '\\') {
      ++i;
      continue;
    }
    CHECK(out[i] != '"', "python string of %s: an unescaped quote in %s", label, out);
  }

  text_escape_utf8(out, sizeof out, in);
  CHECK(valid_utf8(out), "utf8 of %s", label);
  if (valid_utf8(in)) CHECK(strcmp(out, in) == 0, "utf8 changed the valid %s", label);
  CHECK(text_is_utf8(in) == valid_utf8(in), "text_is_utf8 of %s", label);
}

static void exact_outputs(void) {
  /* empty and NULL */
  text_escape_fn all[] = {text_escape_python_comment, text_escape_xml, text_escape_html,
                          text_escape_xml_comment, text_escape_utf8};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) {
    expect(all[i], "an escape", "", "");
    expect(all[i], "an escape", NULL, "");
  }
  expect(text_escape_python_string, "python_string", "", "\"\"");
  expect(text_escape_python_string, "python_string", NULL, "\"\"");

  expect(text_escape_python_comment, "python_comment", "a\nimport os\r\tb\\c \"\"\" '",
         "a\\nimport os\\r\\tb\\\\c \"\"\" '");
  expect(text_escape_python_comment, "python_comment", "\x01\x1b\x7f", "\\x01\\x1b\\x7f");
  expect(text_escape_python_comment, "python_comment", "\xc2\x85|\xe2\x80\xa8|\xe2\x80\xae",
         "\\xc2\\x85|\\xe2\\x80\\xa8|\\xe2\\x80\\xae"); /* NEL, LS, RLO */
  expect(text_escape_python_comment, "python_comment", "caf\xc3\xa9 -->", "caf\xc3\xa9 -->");
  expect(text_escape_python_comment, "python_comment", "\xff\xc3(", "\\xff\\xc3(");

  expect(text_escape_xml_comment, "xml_comment", "a--b", "a\\x2d-b");
  expect(text_escape_xml_comment, "xml_comment", "-->", "\\x2d->");
  expect(text_escape_xml_comment, "xml_comment", "---", "\\x2d\\x2d\\x2d");
  expect(text_escape_xml_comment, "xml_comment", "a-", "a\\x2d");
  expect(text_escape_xml_comment, "xml_comment", "-a-b", "\\x2da-b");
  expect(text_escape_xml_comment, "xml_comment", "<!-- x\n", "<!\\x2d- x\\n");

  expect(text_escape_xml, "xml", "&<>\"'", "&amp;&lt;&gt;&quot;&#39;");
  expect(text_escape_xml, "xml", "</script><script>", "&lt;/script&gt;&lt;script&gt;");
  expect(text_escape_xml, "xml", "\t\n\r", "&#9;&#10;&#13;");
  expect(text_escape_xml, "xml", "\x01|\x7f|\xc2\x85|\xef\xbf\xbe",
         "\xef\xbf\xbd|\xef\xbf\xbd|\xef\xbf\xbd|\xef\xbf\xbd");
  expect(text_escape_xml, "xml", "\xe2\x80\xa8\xe2\x81\xa6\xef\xbb\xbf",
         "&#x2028;&#x2066;&#xfeff;");
  expect(text_escape_xml, "xml", "caf\xc3\xa9 \xf0\x9f\x98\x80", "caf\xc3\xa9 \xf0\x9f\x98\x80");
  expect(text_escape_html, "html", "<b a=\"1\">&amp;", "&lt;b a=&quot;1&quot;&gt;&amp;amp;");

  expect(text_escape_python_string, "python_string", "\"\"\"", "\"\\\"\\\"\\\"\"");
  expect(text_escape_python_string, "python_string", "a\\b\n'\r\t", "\"a\\\\b\\n'\\r\\t\"");
  expect(text_escape_python_string, "python_string", "\x01\x7f", "\"\\x01\\x7f\"");
  expect(text_escape_python_string, "python_string", "\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80",
         "\"\\xe9\\u20ac\\U0001f600\"");
  expect(text_escape_python_string, "python_string", "\xff\xc3(", "\"\\udcff\\udcc3(\"");

  expect(text_escape_utf8, "utf8", "a\x01\"\\", "a\x01\"\\");
  expect(text_escape_utf8, "utf8", "\xff", "\xef\xbf\xbd");

  /* invalid UTF-8: each byte on its own */
  static const char *const invalid[] = {
      "\x80", "\xc0\xaf", "\xed\xa0\x80", "\xf4\x90\x80\x80", "\xe2\x82", "\xf0\x9f\x98", "\xc3"};
  for (size_t i = 0; i < sizeof invalid / sizeof invalid[0]; ++i) {
    char want[64] = "", piece[8];
    for (const unsigned char *s = (const unsigned char *)invalid[i]; *s; ++s) {
      snprintf(piece, sizeof piece, "\\x%02x", *s);
      strcat(want, piece);
    }
    expect(text_escape_python_comment, "python_comment (invalid UTF-8)", invalid[i], want);
  }
}

/* Every control character, each alone and all at once. */
static void control_characters(void) {
  char all[40];
  size_t k = 0;
  for (int c = 1; c < 0x20; ++c) all[k++] = (char)c;
  all[k++] = 0x7f;
  all[k] = '\0';
  check_properties(all, "all control characters");
  char *xml = text_escape_alloc(text_escape_xml, all);
  CHECK(xml && !has_control_byte(xml), "xml of all control characters");
  free(xml);
}

/* Every one- and two-byte string, and random strings of up to 8 bytes
 * (a fixed seed: the same strings every run). */
static void every_short_string(void) {
  char in[16];
  for (int a = 1; a < 256; ++a) {
    in[0] = (char)a, in[1] = '\0';
    check_properties(in, "a one-byte string");
    for (int b = 1; b < 256; ++b) {
      in[1] = (char)b, in[2] = '\0';
      check_properties(in, "a two-byte string");
    }
  }
  uint64_t state = 12345;
  static const unsigned char alphabet[] = {'-',  '\\', '<',  '&',  '"',  '\'', '\n', 'a',
                                           0xc2, 0x85, 0xe2, 0x80, 0xa8, 0xef, 0xbf, 0xff};
  for (int round = 0; round < 200000; ++round) {
    state = state * 6364136223846793005u + 1442695040888963407u;
    int n = 1 + (int)(state >> 61);
    for (int i = 0; i < n; ++i) {
      state = state * 6364136223846793005u + 1442695040888963407u;
      unsigned r = (unsigned)(state >> 33);
      in[i] = (char)(r & 16 ? alphabet[r & 15] : 1 + (r >> 8) % 255);
    }
    in[n] = '\0';
    check_properties(in, "a random string");
  }
}

static void long_text_and_short_buffers(void) {
  size_t n = 100000;
  char *dashes = malloc(n + 1);
  memset(dashes, '-', n);
  dashes[n] = '\0';
  char *out = text_escape_alloc(text_escape_xml_comment, dashes);
  CHECK(out && strlen(out) == 4 * n && !strstr(out, "--"), "100000 dashes in a comment");
  CHECK(text_escape_xml_comment(NULL, 0, dashes) == 4 * n, "the length without a buffer");
  free(out);
  free(dashes);

  /* "a&b" is "a&amp;b" (7): cut before the escape that does not fit whole */
  char small[8];
  memset(small, 'X', sizeof small);
  CHECK(text_escape_xml(small, 7, "a&b") == 7 && strcmp(small, "a&amp;") == 0, "size 7: %s", small);
  CHECK(text_escape_xml(small, 5, "a&b") == 7 && strcmp(small, "a") == 0, "size 5: %s", small);
  CHECK(text_escape_xml(small, 8, "a&b") == 7 && strcmp(small, "a&amp;b") == 0, "size 8: %s",
        small);
  CHECK(text_escape_python_string(small, 1, "x") == 3 && small[0] == '\0', "size 1");
  small[0] = 'X';
  CHECK(text_escape_python_comment(small, 0, "abc") == 3 && small[0] == 'X',
        "size 0 writes nothing");

  FILE *f = tmpfile();
  if (f) {
    char *big = malloc(3001);
    for (int i = 0; i < 3000; ++i) big[i] = "<&\n"[i % 3];
    big[3000] = '\0';
    CHECK(text_escape_fputs(f, text_escape_html, big) == 0, "fputs of a long text");
    CHECK(ftell(f) == 1000 * (4 + 5 + 5), "fputs wrote %ld bytes", ftell(f));
    free(big);
    fclose(f);
  }
  /* written to a file as into a buffer, for every syntax */
  text_escape_fn all[] = {text_escape_python_comment, text_escape_python_string, text_escape_xml,
                          text_escape_html,           text_escape_xml_comment,   text_escape_utf8};
  const char *mixed = "-a--b\n<&>\"'\\ \x01\xc2\x85\xe2\x80\xa8\xff caf\xc3\xa9-";
  for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) {
    char buffer[256], written[256] = "";
    all[i](buffer, sizeof buffer, mixed);
    FILE *g = tmpfile();
    if (!g) continue;
    CHECK(text_escape_fputs(g, all[i], mixed) == 0, "fputs %zu", i);
    rewind(g);
    size_t got = fread(written, 1, sizeof written - 1, g);
    written[got] = '\0';
    fclose(g);
    CHECK(strcmp(buffer, written) == 0, "syntax %zu: the file has %s, the buffer %s", i, written,
          buffer);
  }
}

/* For Python to read back (tests/check_python_literals.py): one line per
 * input, its bytes in hex, a tab, its Python string literal. */
static void write_python_literals(const char *path) {
  static const char *const inputs[] = {"plain",
                                       "",
                                       "\"\"\"",
                                       "'''",
                                       "a\\b\\",
                                       "\n\r\t\x01\x1b\x7f",
                                       "\xc2\x85\xe2\x80\xa8\xe2\x80\xae",
                                       "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80",
                                       "\xff\xfe\xc3(\xe2\x82",
                                       "\xed\xa0\x80 \xc0\xaf",
                                       "\"); __import__('os').system('x') #"};
  FILE *f = fopen(path, "w");
  CHECK(f != NULL, "cannot write %s", path);
  if (!f) return;
  for (size_t i = 0; i < sizeof inputs / sizeof inputs[0]; ++i) {
    for (const unsigned char *s = (const unsigned char *)inputs[i]; *s; ++s) fprintf(f, "%02x", *s);
    fputc('\t', f);
    text_escape_fputs(f, text_escape_python_string, inputs[i]);
    fputc('\n', f);
  }
  CHECK(fclose(f) == 0, "writing %s", path);
}

int main(int argc, char **argv) {
  exact_outputs();
  control_characters();
  every_short_string();
  long_text_and_short_buffers();
  if (argc > 1) write_python_literals(argv[1]);
  return check_finish("test_text_escape");
}
