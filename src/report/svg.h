/* A small SVG writer for the report's plots: a plot area with linear (or
 * log10) axes, polylines, bars and text. Private to src/report. */
#ifndef CLAYFIT_REPORT_SVG_H
#define CLAYFIT_REPORT_SVG_H

#include <stdio.h>

#include "clayfit/status.h"

typedef struct svg_plot {
  FILE *file;
  double x0, x1, y0, y1;           /* data ranges */
  int log_y;                       /* y on a log10 scale (y0, y1 > 0) */
  int no_x_ticks;                  /* categories along x: no ticks or numbers */
  double left, top, width, height; /* the plot area, pixels */
} svg_plot;

/* Open path and write the header of a W × H picture with a title; the
 * plot area leaves room for the axes' labels. */
cf_status svg_begin(svg_plot *plot, const char *path, int width, int height, const char *title,
                    cf_error *err);
/* Frame, ticks and labels of the axes. */
void svg_axes(svg_plot *plot, const char *x_label, const char *y_label);
/* A polyline through (x[i], y[i]) (non-finite points break it). */
void svg_line(svg_plot *plot, const double *x, const double *y, int n, const char *colour,
              double width, const char *dash);
/* Bars from the x axis: bar i spans [x[i], x[i] + w) up to y[i]. */
void svg_bars(svg_plot *plot, const double *x, const double *y, int n, double w,
              const char *colour);
/* A legend line at row `row` of the top-right corner. */
void svg_legend(svg_plot *plot, int row, const char *colour, const char *text);
/* Text at picture coordinates. */
void svg_text(svg_plot *plot, double px, double py, const char *anchor, const char *text);

/* Text escaped for SVG (XML) text and attribute values: the core's
 * text_escape_xml (core/text_escape.h); NULL writes nothing. */
void svg_escape(FILE *f, const char *text);
/* Close the file; CF_EIO naming path if writing failed. */
cf_status svg_end(svg_plot *plot, const char *path, cf_error *err);

/* Picture coordinates of a data point. */
double svg_px(const svg_plot *plot, double x);
double svg_py(const svg_plot *plot, double y);

#endif /* CLAYFIT_REPORT_SVG_H */
