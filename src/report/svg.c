/* A small SVG writer (svg.h). */
#include "svg.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "core/text_escape.h"

double svg_px(const svg_plot *p, double x) {
  return p->left + (x - p->x0) / (p->x1 - p->x0) * p->width;
}

double svg_py(const svg_plot *p, double y) {
  double t = p->log_y ? (log10(y) - log10(p->y0)) / (log10(p->y1) - log10(p->y0))
                      : (y - p->y0) / (p->y1 - p->y0);
  return p->top + (1.0 - t) * p->height;
}

void svg_escape(FILE *f, const char *text) {
  text_escape_fputs(f, text_escape_xml, text);
}

cf_status svg_begin(svg_plot *p, const char *path, int width, int height, const char *title,
                    cf_error *err) {
  p->file = fopen(path, "w");
  if (!p->file) return cf_error_set(err, CF_EIO, "%s: cannot write: %s", path, strerror(errno));
  p->left = 80.0;
  p->top = 36.0;
  p->width = width - 100.0;
  p->height = height - 86.0;
  fprintf(p->file,
          "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
          "viewBox=\"0 0 %d %d\" font-family=\"sans-serif\" font-size=\"12\">\n"
          "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n<text x=\"%d\" y=\"20\" "
          "text-anchor=\"middle\" font-size=\"14\">",
          width, height, width, height, width / 2);
  svg_escape(p->file, title);
  fputs("</text>\n", p->file);
  return CF_OK;
}

/* A tick value, short. */
static void tick_label(char *out, size_t size, double v) {
  if (v != 0.0 && (fabs(v) >= 1e4 || fabs(v) < 1e-2))
    snprintf(out, size, "%.1e", v);
  else
    snprintf(out, size, "%.3g", v);
}

void svg_axes(svg_plot *p, const char *x_label, const char *y_label) {
  FILE *f = p->file;
  fprintf(f,
          "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
          "stroke=\"black\"/>\n",
          p->left, p->top, p->width, p->height);
  char label[32];
  for (int i = 0; i <= 5; ++i) {
    double x = p->x0 + (p->x1 - p->x0) * i / 5.0, px = svg_px(p, x);
    tick_label(label, sizeof label, x);
    if (!p->no_x_ticks) {
      fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\"/>", px,
              p->top + p->height, px, p->top + p->height + 4);
      fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n", px,
              p->top + p->height + 17, label);
    }
    double y = p->log_y ? pow(10.0, log10(p->y0) + (log10(p->y1) - log10(p->y0)) * i / 5.0)
                        : p->y0 + (p->y1 - p->y0) * i / 5.0;
    double py = svg_py(p, y);
    tick_label(label, sizeof label, y);
    fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\"/>",
            p->left - 4, py, p->left, py);
    fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n", p->left - 6, py + 4,
            label);
  }
  fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">", p->left + p->width / 2,
          p->top + p->height + 36);
  svg_escape(f, x_label);
  fprintf(f,
          "</text>\n<text transform=\"translate(14 %.1f) rotate(-90)\" "
          "text-anchor=\"middle\">",
          p->top + p->height / 2);
  svg_escape(f, y_label);
  fputs("</text>\n", f);
}

void svg_line(svg_plot *p, const double *x, const double *y, int n, const char *colour,
              double width, const char *dash) {
  int open = 0;
  for (int i = 0; i < n; ++i) {
    int ok = isfinite(x[i]) && isfinite(y[i]) && (!p->log_y || y[i] > 0.0);
    if (ok && !open) {
      fprintf(p->file, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"%g\"%s%s%s points=\"",
              colour, width, dash ? " stroke-dasharray=\"" : "", dash ? dash : "",
              dash ? "\"" : "");
      open = 1;
    }
    if (ok) fprintf(p->file, "%.1f,%.1f ", svg_px(p, x[i]), svg_py(p, y[i]));
    if (!ok && open) {
      fputs("\"/>\n", p->file);
      open = 0;
    }
  }
  if (open) fputs("\"/>\n", p->file);
}

void svg_bars(svg_plot *p, const double *x, const double *y, int n, double w, const char *colour) {
  double base = svg_py(p, p->y0);
  for (int i = 0; i < n; ++i) {
    if (!isfinite(y[i]) || (p->log_y && y[i] <= p->y0)) continue;
    double top = svg_py(p, y[i]), px = svg_px(p, x[i]);
    fprintf(p->file, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n",
            px, top, fmax(0.5, svg_px(p, x[i] + w) - px - 0.5), fmax(0.0, base - top), colour);
  }
}

void svg_legend(svg_plot *p, int row, const char *colour, const char *text) {
  double x = p->left + p->width - 200, y = p->top + 16 + 16 * row;
  fprintf(p->file,
          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
          "stroke-width=\"2\"/><text x=\"%.1f\" y=\"%.1f\">",
          x, y - 4, x + 20, y - 4, colour, x + 26, y);
  svg_escape(p->file, text);
  fputs("</text>\n", p->file);
}

void svg_text(svg_plot *p, double px, double py, const char *anchor, const char *text) {
  fprintf(p->file, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"%s\">", px, py, anchor);
  svg_escape(p->file, text);
  fputs("</text>\n", p->file);
}

cf_status svg_end(svg_plot *p, const char *path, cf_error *err) {
  fputs("</svg>\n", p->file);
  int failed = ferror(p->file), why = failed ? errno : 0;
  if (fclose(p->file) != 0) failed = 1, why = errno;
  p->file = NULL;
  return failed
             ? cf_error_set(err, CF_EIO, "%s: could not write: %s", path, strerror(why ? why : EIO))
             : CF_OK;
}
