// clayfit-peers' SciPy contestant: least_squares ('trf', the 2-point
// Jacobian) over a vectorised NumPy model, run by scripts/peer_scipy.py on
// the observations written as .npy files.
#include <jansson.h>

#include <cstdio>
#include <string>
#include <vector>

#include <stdlib.h>
#include <unistd.h>

#include "peers.h"
#include "peers_clayfit.h"

namespace peers {
namespace {

// A .npy file (format 1.0) of float64, C order, with the given shape.
bool WriteNpy(const std::string &path, const std::vector<double> &a,
              const std::vector<size_t> &shape) {
  std::string dims;
  for (size_t s : shape) dims += std::to_string(s) + ",";
  if (shape.size() > 1) dims.pop_back();
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + dims + "), }";
  size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header += '\n';
  FILE *f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const unsigned char magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
  unsigned short len = static_cast<unsigned short>(header.size());
  unsigned char lenb[2] = {static_cast<unsigned char>(len & 0xff),
                           static_cast<unsigned char>(len >> 8)};
  bool ok = std::fwrite(magic, 1, 8, f) == 8 && std::fwrite(lenb, 1, 2, f) == 2 &&
            std::fwrite(header.data(), 1, header.size(), f) == header.size() &&
            std::fwrite(a.data(), sizeof(double), a.size(), f) == a.size();
  return std::fclose(f) == 0 && ok;
}

// One word for `sh -c`: single quotes, a ' inside written '\''.
std::string ShellQuoted(const std::string &word) {
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace

std::string JsonArray(const std::vector<double> &a) {
  std::string s = "[";
  char buf[40];
  for (size_t i = 0; i < a.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%.17g", i ? ", " : "", a[i]);
    s += buf;
  }
  return s + "]";
}

// SciPy's least_squares through scripts/peer_scipy.py: the observations,
// the C evaluator's prediction at the start (the script checks its model
// against it) and the problem's settings in a directory, the result as JSON
// on the script's stdout.
void SolveScipy(const Data &d, const std::vector<double> &start, const std::vector<double> &pred_c,
                const Options &o, Outcome *out) {
  char dir_template[4096];
  std::snprintf(dir_template, sizeof dir_template, "%s/clayfit-peers-XXXXXX", o.work.c_str());
  if (mkdtemp(dir_template) == nullptr) {
    out->note = "cannot make a work directory under " + o.work;
    return;
  }
  const std::string dir = dir_template;
  const size_t n = d.count, L = static_cast<size_t>(d.lights);
  bool ok = WriteNpy(dir + "/normal.npy", d.n, {n, 3}) &&
            WriteNpy(dir + "/view.npy", d.v, {n, 3}) &&
            WriteNpy(dir + "/light.npy", d.l, {n, L, 3}) &&
            WriteNpy(dir + "/irradiance.npy", d.e, {n, L, 3}) &&
            WriteNpy(dir + "/measured.npy", d.y, {n, 3}) &&
            WriteNpy(dir + "/prediction_c.npy", pred_c, {n, 3});
  FILE *meta = std::fopen((dir + "/problem.json").c_str(), "w");
  if (meta != nullptr) {
    std::fprintf(meta,
                 "{\"model\": \"%s\", \"start\": %s, \"lower\": %s, \"upper\": %s, "
                 "\"ftol\": 1e-10, \"xtol\": 1e-10, \"gtol\": 1e-12, \"max_iterations\": %d}\n",
                 cf_model_info_get(d.model)->code, JsonArray(start).c_str(),
                 JsonArray(d.lower).c_str(), JsonArray(d.upper).c_str(), o.max_iterations);
    ok = std::fclose(meta) == 0 && ok;
  } else {
    ok = false;
  }
  if (!ok) {
    out->note = "cannot write the problem to " + dir;
    return;
  }
  const std::string command =
      ShellQuoted(o.python) + " " + ShellQuoted(o.script) + " " + ShellQuoted(dir);
  double t0 = peers_now();
  FILE *pipe = popen(command.c_str(), "r");
  std::string text;
  if (pipe != nullptr) {
    char buf[4096];
    size_t got;
    while ((got = std::fread(buf, 1, sizeof buf, pipe)) > 0) text.append(buf, got);
  }
  int status = pipe != nullptr ? pclose(pipe) : -1;
  double wall = peers_now() - t0;
  for (const char *name : {"normal", "view", "light", "irradiance", "measured", "prediction_c"})
    std::remove((dir + "/" + name + ".npy").c_str());
  std::remove((dir + "/problem.json").c_str());
  rmdir(dir.c_str());
  json_error_t jerr;
  json_t *doc = json_loads(text.c_str(), 0, &jerr);
  if (doc == nullptr) {
    out->note = "peer_scipy.py gave no JSON (exit status " + std::to_string(status) + ")";
    return;
  }
  if (json_t *skip = json_object_get(doc, "skipped"); json_is_string(skip)) {
    out->skipped = true;
    out->note = json_string_value(skip);
    json_decref(doc);
    return;
  }
  out->ran = true;
  out->seconds = json_number_value(json_object_get(doc, "seconds"));
  out->solve_seconds = out->seconds;
  out->solver_cost = json_number_value(json_object_get(doc, "cost"));
  out->evaluations = static_cast<int>(json_integer_value(json_object_get(doc, "nfev")));
  json_t *njev = json_object_get(doc, "njev");
  out->jacobians = json_is_integer(njev) ? static_cast<int>(json_integer_value(njev)) : -1;
  out->iterations = out->jacobians;
  out->model_error = json_number_value(json_object_get(doc, "model_error"));
  out->model_ok = out->model_error <= kModelTolerance;
  json_t *x = json_object_get(doc, "x");
  for (size_t k = 0; k < json_array_size(x); ++k)
    out->params.push_back(json_number_value(json_array_get(x, k)));
  const char *message = json_string_value(json_object_get(doc, "message"));
  out->note = message != nullptr ? message : "";
  out->note += " (python wall " + std::to_string(wall) + " s with start-up and loading)";
  json_decref(doc);
  if (static_cast<int>(out->params.size()) != d.dim) out->ran = false, out->note = "no x";
}

}  // namespace peers
