/* The material library's gallery page (include/clayfit/gallery.h): static
 * cards, an inline style, and an inline script that only sorts and filters
 * them. Built in memory and written whole (cf_write_file). */
#include "clayfit/gallery.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/model.h"
#include "core/file.h"
#include "core/json_reader.h"
#include "core/text_escape.h"

static const char *const state_names[] = {"fitted", "failed", "missing"};

/* Untrusted text on the page (element text or a quoted attribute value). */
static void html(FILE *f, const char *text) {
  text_escape_fputs(f, text_escape_html, text);
}

/* A relative path as a URL: every byte but the unreserved characters of
 * RFC 3986 and `/` percent-encoded, so that `:` cannot start a scheme
 * (`javascript:`), `#` and `?` stay part of the file's name, and the
 * result needs no further escaping in a quoted attribute. */
static void url_path(FILE *f, const char *path) {
  static const char hex[] = "0123456789ABCDEF";
  for (const unsigned char *p = (const unsigned char *)path; *p; ++p) {
    int keep = (*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') ||
               strchr("-._~/", *p) != NULL;
    if (keep)
      fputc(*p, f);
    else
      fprintf(f, "%%%c%c", hex[*p >> 4], hex[*p & 15]);
  }
}

/* ---- checking the entries ---- */

static cf_status check_path(const char *path, size_t i, const char *what, cf_error *err) {
  if (path && path[0] == '/')
    return cf_error_set(err, CF_EINVAL,
                        "gallery entry %zu: the %s path must be relative to the page (it starts "
                        "with '/')",
                        i, what);
  return CF_OK;
}

static cf_status check_entry(const cf_gallery_entry *e, size_t i, cf_error *err) {
  if (!e->name) return cf_error_set(err, CF_EINVAL, "gallery entry %zu: no name", i);
  if ((unsigned)e->state > CF_GALLERY_MISSING)
    return cf_error_set(err, CF_EINVAL, "gallery entry %zu: unknown state %d", i, (int)e->state);
  if (e->tag_count > CF_GALLERY_MAX_TAGS || (e->tag_count && !e->tags))
    return cf_error_set(err, CF_EINVAL, "gallery entry %zu: %zu tags (at most %d)", i, e->tag_count,
                        CF_GALLERY_MAX_TAGS);
  for (size_t t = 0; t < e->tag_count; ++t)
    if (!e->tags[t].key || !e->tags[t].value)
      return cf_error_set(err, CF_EINVAL, "gallery entry %zu: tag %zu has no key or value", i, t);
  if (e->param_count > CF_GALLERY_MAX_PARAMS || (e->param_count && !e->params))
    return cf_error_set(err, CF_EINVAL, "gallery entry %zu: %zu parameters (at most %d)", i,
                        e->param_count, CF_GALLERY_MAX_PARAMS);
  for (size_t k = 0; k < e->param_count; ++k) {
    const cf_gallery_param *p = &e->params[k];
    if (!p->name || (p->components != 1 && p->components != 3))
      return cf_error_set(err, CF_EINVAL,
                          "gallery entry %zu: parameter %zu has no name or %d components "
                          "(1 or 3)",
                          i, k, p->components);
    for (int c = 0; c < p->components; ++c)
      if (!isfinite(p->value[c]))
        return cf_error_set(err, CF_EINVAL, "gallery entry %zu: parameter %s[%d] is not finite", i,
                            p->name, c);
  }
  cf_status s = check_path(e->thumbnail, i, "thumbnail", err);
  return s == CF_OK ? check_path(e->report, i, "report", err) : s;
}

/* ---- the data the script sorts and filters on ---- */

/* The sort key of each parameter component: "albedo" (an RGB parameter's
 * mean) and "albedo r", "albedo g", "albedo b". */
static const char *const channel_suffix[3] = {" r", " g", " b"};

static int add_params(json_t *p, const cf_gallery_entry *e) {
  int failed = 0;
  for (size_t k = 0; k < e->param_count; ++k) {
    const cf_gallery_param *q = &e->params[k];
    char *name = text_escape_alloc(text_escape_utf8, q->name);
    if (!name) return -1;
    double mean = 0.0;
    for (int c = 0; c < q->components; ++c) mean += q->value[c] / q->components;
    failed |= json_object_set_new(p, name, json_real(mean));
    for (int c = 0; q->components == 3 && c < 3; ++c) {
      size_t n = strlen(name) + 3;
      char *key = malloc(n);
      if (!key) {
        failed = -1;
        break;
      }
      snprintf(key, n, "%s%s", name, channel_suffix[c]);
      failed |= json_object_set_new(p, key, json_real(q->value[c]));
      free(key);
    }
    free(name);
  }
  return failed ? -1 : 0;
}

/* The card's data-entry attribute: {name, state, model, rmse, reason,
 * tags: {key: value}, p: {sort key: value}} as JSON, HTML-escaped. */
static int card_data(FILE *f, const cf_gallery_entry *e) {
  json_t *o = json_object(), *tags = json_object(), *p = json_object();
  int failed = !o || !tags || !p;
  if (!failed) {
    failed |= json_object_set_new(o, "name", json_text(e->name));
    failed |= json_object_set_new(o, "state", json_string(state_names[e->state]));
    failed |= json_object_set_new(o, "model", e->model ? json_text(e->model) : json_null());
    failed |= json_object_set_new(o, "rmse", json_real_or_null(e->relative_rmse));
    failed |= json_object_set_new(o, "reason", json_text(e->reason));
    for (size_t t = 0; !failed && t < e->tag_count; ++t) {
      char *key = text_escape_alloc(text_escape_utf8, e->tags[t].key);
      failed |= !key || json_object_set_new(tags, key, json_text(e->tags[t].value));
      free(key);
    }
    failed |= add_params(p, e);
    failed |= json_object_set(o, "tags", tags) | json_object_set(o, "p", p);
  }
  char *text = failed ? NULL : json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII);
  json_decref(o);
  json_decref(tags);
  json_decref(p);
  if (!text) return -1;
  html(f, text);
  free(text);
  return 0;
}

/* ---- the controls: sort keys and tag values over every entry ---- */

typedef struct pair {
  const char *key, *value;
} pair;

static int compare_pairs(const void *a, const void *b) {
  const pair *x = a, *y = b;
  int c = strcmp(x->key, y->key);
  return c ? c : strcmp(x->value ? x->value : "", y->value ? y->value : "");
}

/* Every distinct tag (key, value), and every parameter (name, NULL),
 * sorted. */
static pair *collect(const cf_gallery_entry *entries, size_t count, int tags, size_t *n) {
  size_t total = 0;
  for (size_t i = 0; i < count; ++i) total += tags ? entries[i].tag_count : entries[i].param_count;
  pair *list = malloc((total ? total : 1) * sizeof *list);
  if (!list) return NULL;
  size_t m = 0;
  for (size_t i = 0; i < count; ++i) {
    const cf_gallery_entry *e = &entries[i];
    size_t k_end = tags ? e->tag_count : e->param_count;
    for (size_t k = 0; k < k_end; ++k)
      list[m++] = tags ? (pair){e->tags[k].key, e->tags[k].value}
                       : (pair){e->params[k].name, e->params[k].components == 3 ? "3" : NULL};
  }
  qsort(list, m, sizeof *list, compare_pairs);
  size_t u = 0;
  for (size_t k = 0; k < m; ++k)
    if (u == 0 || compare_pairs(&list[u - 1], &list[k]) != 0) list[u++] = list[k];
  *n = u;
  return list;
}

/* A parameter's sort keys as <option>s (the mean, then each channel). */
static void param_options(FILE *f, const pair *params, size_t n) {
  for (size_t k = 0; k < n; ++k) {
    if (k && strcmp(params[k - 1].key, params[k].key) == 0) continue;
    int rgb = params[k].value != NULL;
    for (int c = -1; c < (rgb ? 3 : 0); ++c) {
      fputs("<option value=\"", f);
      html(f, params[k].key);
      if (c >= 0) fputs(channel_suffix[c], f);
      fputs("\">", f);
      html(f, params[k].key);
      fputs(c >= 0 ? channel_suffix[c] : rgb ? " (mean)" : "", f);
      fputs("</option>", f);
    }
  }
}

static void tag_filters(FILE *f, const pair *tags, size_t n) {
  for (size_t k = 0; k < n; ++k) {
    if (k == 0 || strcmp(tags[k - 1].key, tags[k].key) != 0) {
      if (k) fputs("</select></label>\n", f);
      fputs("<label>", f);
      html(f, tags[k].key);
      fputs(" <select class=\"tag-filter\" data-key=\"", f);
      html(f, tags[k].key);
      fputs("\"><option value=\"\">any</option>", f);
    }
    fputs("<option value=\"", f);
    html(f, tags[k].value);
    fputs("\">", f);
    html(f, tags[k].value);
    fputs("</option>", f);
  }
  if (n) fputs("</select></label>\n", f);
}

static cf_status controls(FILE *f, const cf_gallery_entry *entries, size_t count, cf_error *err) {
  size_t np = 0, nt = 0;
  pair *params = collect(entries, count, 0, &np), *tags = collect(entries, count, 1, &nt);
  if (!params || !tags) {
    free(params);
    free(tags);
    return cf_error_set(err, CF_ENOMEM, "gallery: out of memory");
  }
  fputs(
      "<form id=\"controls\" onsubmit=\"return false\">\n<noscript><p>Sorting and filtering "
      "need JavaScript; the cards below are in the library's order.</p></noscript>\n"
      "<div>Sort: <button type=\"button\" data-sort=\"name\">name</button> "
      "<button type=\"button\" data-sort=\"rmse\">relative RMSE</button> "
      "<button type=\"button\" data-sort=\"model\">model</button> "
      "<label>parameter <select id=\"sort-param\"><option value=\"\">&mdash;</option>",
      f);
  param_options(f, params, np);
  fputs(
      "</select></label> <span id=\"sort-state\"></span></div>\n"
      "<div>Filter: <label>text <input id=\"filter-text\" type=\"search\" "
      "placeholder=\"name, tag, model, reason\"></label>\n<label>state <select "
      "id=\"filter-state\"><option value=\"\">any</option><option>fitted</option>"
      "<option>failed</option><option>missing</option></select></label>\n",
      f);
  tag_filters(f, tags, nt);
  fputs("<label>parameter <select id=\"filter-param\"><option value=\"\">&mdash;</option>", f);
  param_options(f, params, np);
  fputs(
      "</select></label> <label>from <input id=\"filter-min\" type=\"number\" step=\"any\" "
      "size=\"7\"></label> <label>to <input id=\"filter-max\" type=\"number\" step=\"any\" "
      "size=\"7\"></label></div>\n</form>\n",
      f);
  free(params);
  free(tags);
  return CF_OK;
}

/* ---- the cards ---- */

static void param_row(FILE *f, const cf_gallery_param *p) {
  fputs("<tr><th>", f);
  html(f, p->name);
  fputs("</th><td>", f);
  for (int c = 0; c < p->components; ++c) fprintf(f, "%s%.4g", c ? " / " : "", p->value[c]);
  fputs("</td><td>", f);
  int any = 0;
  for (int c = 0; c < p->components; ++c) any |= isfinite(p->sd[c]);
  if (any) {
    fputs("&plusmn; ", f);
    for (int c = 0; c < p->components; ++c)
      isfinite(p->sd[c]) ? fprintf(f, "%s%.2g", c ? " / " : "", p->sd[c])
                         : fprintf(f, "%s&ndash;", c ? " / " : "");
  } else {
    fputs("no sd", f);
  }
  fputs("</td><td>", f);
  if (p->unit && strcmp(p->unit, "1") != 0) html(f, p->unit);
  fputs("</td></tr>", f);
}

static void card_model(FILE *f, const cf_gallery_entry *e) {
  fputs("<p class=\"fit\">model <b>", f);
  if (e->model && e->model[0]) {
    html(f, e->model);
    cf_model_id id;
    if (cf_model_find(e->model, &id, NULL) == CF_OK) {
      fputs(" (", f);
      html(f, cf_model_info_get(id)->name);
      fputs(")", f);
    }
  } else {
    fputs("&ndash;", f);
  }
  fputs("</b>, relative RMSE <b>", f);
  if (isfinite(e->relative_rmse))
    fprintf(f, "%.3g %%", 100.0 * e->relative_rmse);
  else
    fputs("&ndash;", f);
  fputs("</b></p>\n", f);
}

static cf_status card(FILE *f, const cf_gallery_entry *e, cf_error *err) {
  fprintf(f, "<article class=\"card %s\" data-entry=\"", state_names[e->state]);
  if (card_data(f, e) != 0) return cf_error_set(err, CF_ENOMEM, "gallery: out of memory");
  fputs("\">\n", f);
  if (e->thumbnail) {
    fputs("<img src=\"", f);
    url_path(f, e->thumbnail);
    fputs("\" width=\"160\" height=\"160\" alt=\"the fitted sphere of ", f);
    html(f, e->name);
    fputs("\">\n", f);
  } else {
    fputs("<div class=\"nothumb\">no thumbnail</div>\n", f);
  }
  fputs("<h2>", f);
  html(f, e->name);
  fputs("</h2>\n", f);
  if (e->state == CF_GALLERY_FAILED) {
    fputs("<p class=\"reason\"><b>failed</b>: ", f);
    html(f, e->reason && e->reason[0] ? e->reason : "no reason recorded");
    fputs("</p>\n", f);
  } else if (e->state == CF_GALLERY_MISSING) {
    fputs("<p class=\"reason\"><b>not fitted</b></p>\n", f);
  }
  if (e->tag_count) fputs("<ul class=\"tags\">", f);
  for (size_t t = 0; t < e->tag_count; ++t) {
    fputs("<li><span>", f);
    html(f, e->tags[t].key);
    fputs("</span> ", f);
    html(f, e->tags[t].value);
    fputs("</li>", f);
  }
  if (e->tag_count) fputs("</ul>\n", f);
  if (e->state == CF_GALLERY_FITTED) card_model(f, e);
  if (e->param_count) fputs("<table>", f);
  for (size_t k = 0; k < e->param_count; ++k) param_row(f, &e->params[k]);
  if (e->param_count) fputs("</table>\n", f);
  if (e->report) {
    fputs("<p><a href=\"", f);
    url_path(f, e->report);
    fputs(e->state == CF_GALLERY_FAILED ? "\">failure details</a></p>\n" : "\">report</a></p>\n",
          f);
  }
  fputs("</article>\n", f);
  return CF_OK;
}

/* ---- the page ---- */

static void head(FILE *f, const char *title, const cf_gallery_entry *entries, size_t count) {
  size_t n[3] = {0, 0, 0};
  for (size_t i = 0; i < count; ++i) ++n[entries[i].state];
  fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>", f);
  html(f, title);
  fputs(
      "</title>\n<style>\nbody{font-family:sans-serif;margin:20px}\n"
      "#controls div{margin:4px 0}#controls label{margin-right:10px}\n"
      "button.active{font-weight:bold}\n"
      "#cards{display:flex;flex-wrap:wrap;gap:12px;align-items:flex-start}\n"
      ".card{border:1px solid #bbb;border-radius:6px;padding:8px;width:340px;"
      "overflow-wrap:anywhere}\n"
      ".card img,.nothumb{display:block;width:160px;height:160px;margin:0 auto}\n"
      ".nothumb{background:#eee;color:#666;text-align:center;line-height:160px}\n"
      ".card h2{font-size:16px;margin:6px 0}.card.failed{border-color:#c03030;background:#fff4f4}"
      "\n.reason{color:#a02020}.tags{padding:0;margin:4px 0}.tags li{display:inline-block;"
      "background:#eef;border-radius:3px;padding:1px 5px;margin:2px;font-size:12px}"
      ".tags span{color:#557}\n"
      "table{border-collapse:collapse;font-size:12px}th{text-align:left;font-weight:normal;"
      "padding-right:6px;white-space:nowrap}td{padding-right:6px;overflow-wrap:normal}\n"
      "input[type=number]{width:7em}[hidden]{display:none!important}\n"
      "</style></head><body>\n<h1>",
      f);
  html(f, title);
  fprintf(f,
          "</h1>\n<p>%zu entries: %zu fitted, %zu failed, %zu not fitted. Thumbnails: the fitted "
          "sphere under the standard light (key upper left, fill right; an albedo-1 Lambertian "
          "surface facing the key at 0.8 of white). <span id=\"shown\"></span></p>\n",
          count, n[CF_GALLERY_FITTED], n[CF_GALLERY_FAILED], n[CF_GALLERY_MISSING]);
}

/* The script: sorts (missing values last either way, ties by name) and
 * filters the cards, and counts the images that loaded into #loaded (what
 * the browser test reads). It reads only the cards' data-entry JSON. */
static const char script[] =
    "<p id=\"loaded\">images: not checked (scripts off)</p>\n<script>\n"
    "(function () {\n"
    "  'use strict';\n"
    "  var box = document.getElementById('cards');\n"
    "  var cards = Array.prototype.slice.call(box.querySelectorAll('article.card'));\n"
    "  var has = function (o, k) { return Object.prototype.hasOwnProperty.call(o, k); };\n"
    "  cards.forEach(function (c) {\n"
    "    c.entry = JSON.parse(c.getAttribute('data-entry'));\n"
    "    var e = c.entry, t = [e.name, e.model || '', e.state, e.reason || ''];\n"
    "    Object.keys(e.tags).forEach(function (k) { t.push(k, e.tags[k]); });\n"
    "    c.text = t.join('\\n').toLowerCase();\n"
    "  });\n"
    "  var key = '', up = true;\n"
    "  function value(c, k) {\n"
    "    var e = c.entry;\n"
    "    if (k === 'name' || k === 'model' || k === 'rmse') return e[k];\n"
    "    return has(e.p, k) ? e.p[k] : null;\n"
    "  }\n"
    "  function compare(a, b) {\n"
    "    var x = value(a, key), y = value(b, key), mx = x === null, my = y === null, r;\n"
    "    if (mx || my) r = mx === my ? 0 : mx ? 1 : -1;\n"
    "    else r = (typeof x === 'string' ? x.localeCompare(y) : x - y) * (up ? 1 : -1);\n"
    "    return r || a.entry.name.localeCompare(b.entry.name);\n"
    "  }\n"
    "  function sort(k) {\n"
    "    if (k === key) up = !up; else { key = k; up = true; }\n"
    "    cards.sort(compare);\n"
    "    cards.forEach(function (c) { box.appendChild(c); });\n"
    "    document.querySelectorAll('button[data-sort]').forEach(function (b) {\n"
    "      b.classList.toggle('active', b.getAttribute('data-sort') === key);\n"
    "    });\n"
    "    document.getElementById('sort-state').textContent =\n"
    "        'sorted by ' + key + (up ? ', ascending' : ', descending');\n"
    "  }\n"
    "  function number(id) {\n"
    "    var v = document.getElementById(id).value;\n"
    "    return v === '' ? null : Number(v);\n"
    "  }\n"
    "  function filter() {\n"
    "    var text = document.getElementById('filter-text').value.toLowerCase();\n"
    "    var state = document.getElementById('filter-state').value;\n"
    "    var param = document.getElementById('filter-param').value;\n"
    "    var lo = number('filter-min'), hi = number('filter-max'), shown = 0;\n"
    "    var tags = Array.prototype.slice.call(document.querySelectorAll('select.tag-filter'));\n"
    "    cards.forEach(function (c) {\n"
    "      var e = c.entry, ok = (!text || c.text.indexOf(text) >= 0) &&\n"
    "          (!state || e.state === state);\n"
    "      tags.forEach(function (s) {\n"
    "        var k = s.getAttribute('data-key');\n"
    "        if (s.value !== '' && !(has(e.tags, k) && e.tags[k] === s.value)) ok = false;\n"
    "      });\n"
    "      if (param && (lo !== null || hi !== null)) {\n"
    "        var v = has(e.p, param) ? e.p[param] : null;\n"
    "        if (v === null || (lo !== null && v < lo) || (hi !== null && v > hi)) ok = false;\n"
    "      }\n"
    "      c.hidden = !ok;\n"
    "      shown += ok;\n"
    "    });\n"
    "    document.getElementById('shown').textContent =\n"
    "        'Showing ' + shown + ' of ' + cards.length + '.';\n"
    "  }\n"
    "  document.querySelectorAll('button[data-sort]').forEach(function (b) {\n"
    "    b.addEventListener('click', function () { sort(b.getAttribute('data-sort')); });\n"
    "  });\n"
    "  document.getElementById('sort-param').addEventListener('change', function () {\n"
    "    if (this.value !== '') { key = ''; sort(this.value); }\n"
    "  });\n"
    "  document.querySelectorAll('#controls input, #controls select').forEach(function (el) {\n"
    "    if (el.id !== 'sort-param') {\n"
    "      el.addEventListener('input', filter);\n"
    "      el.addEventListener('change', filter);\n"
    "    }\n"
    "  });\n"
    "  filter();\n"
    "  window.addEventListener('load', function () {\n"
    "    var all = document.images, ok = 0;\n"
    "    for (var i = 0; i < all.length; ++i) if (all[i].complete && all[i].naturalWidth > 0) "
    "++ok;\n"
    "    document.getElementById('loaded').textContent = 'images loaded: ' + ok + ' of ' + "
    "all.length;\n"
    "  });\n"
    "})();\n"
    "</script>\n</body></html>\n";

static cf_status write_page(FILE *f, const cf_gallery_entry *entries, size_t count,
                            const char *title, cf_error *err) {
  head(f, title, entries, count);
  cf_status s = controls(f, entries, count, err);
  if (s == CF_OK) fputs("<main id=\"cards\">\n", f);
  for (size_t i = 0; s == CF_OK && i < count; ++i) s = card(f, &entries[i], err);
  if (s == CF_OK) {
    fputs("</main>\n", f);
    fputs(script, f);
  }
  return s;
}

cf_status cf_report_write_gallery(const cf_gallery_entry *entries, size_t count, const char *title,
                                  const char *path, cf_error *err) {
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "gallery: an empty path");
  if (count && !entries) return cf_error_set(err, CF_EINVAL, "gallery: no entries");
  for (size_t i = 0; i < count; ++i) {
    cf_status s = check_entry(&entries[i], i, err);
    if (s != CF_OK) return s;
  }
  char *page = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&page, &size);
  if (!f) return cf_error_set(err, CF_ENOMEM, "gallery: out of memory");
  cf_status s = write_page(f, entries, count, title ? title : "clayfit library", err);
  int failed = ferror(f);
  failed |= fclose(f) != 0;
  if (s == CF_OK && failed) s = cf_error_set(err, CF_ENOMEM, "gallery: out of memory");
  if (s == CF_OK) s = cf_write_file(path, page, size, err);
  free(page);
  return s;
}

void cf_gallery_params_from_result(const cf_fit_result *result, cf_gallery_param *params,
                                   size_t *param_count) {
  *param_count = 0;
  const cf_model_info *m = result ? cf_model_info_get(result->model) : NULL;
  if (!m) return;
  for (int k = 0; k < m->param_count; ++k) {
    const cf_param_info *info = cf_param_info_get(m->params[k]);
    cf_gallery_param *p = &params[(*param_count)++];
    p->name = info->name;
    p->unit = info->unit;
    p->components = info->components;
    for (int c = 0; c < 3; ++c) {
      int slot = m->offsets[k] + (c < info->components ? c : 0);
      double sd = result->sd[slot];
      p->value[c] = result->params[slot];
      p->sd[c] = isfinite(sd) && sd > 0.0 ? sd : NAN;
    }
  }
}
