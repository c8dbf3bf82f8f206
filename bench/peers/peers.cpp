// clayfit-peers: clayfit's fit against its peers on the same observations
// in the same run (issue 6). The common problem: the capture's lit,
// unclipped observations (optionally an even subsample), unweighted least
// squares on linear RGB, residual Σ_j f(n, l_j, v) E_j c_i,j − y per
// channel, every parameter of the model free within its bounds (docs/model.md §1.6), one
// start, Levenberg-Marquardt (SciPy: trf) with the same tolerances.
// Contestants: clayfit (fit_problem over lsq.h), Ceres with
// AutoDiffCostFunction and NumericDiffCostFunction (CENTRAL) over the
// templated model (jet_model.h) and with the C evaluator's analytic
// derivatives (ObservationAnalytic), one residual block per observation,
// and SciPy's least_squares over a vectorised NumPy model
// (scripts/peer_scipy.py). Every contestant's final parameters are costed
// again by the C evaluator, so that the costs compared are one definition.
// Times are reported, never asserted. No exception escapes main.
#include <ceres/ceres.h>
#include <glog/logging.h>
#include <jansson.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <unistd.h>

extern "C" {
#include "clayfit/capture.h"
#include "clayfit/model.h"
}
#include "jet_model.h"
#include "peers_clayfit.h"

namespace {

using clayfit_jet::Vec3;

constexpr double kCostTolerance = 1e-6;    // |cost − clayfit's| / clayfit's
constexpr double kModelTolerance = 1e-10;  // relative, of the prediction

struct Options {
  std::string capture, json, python = "/usr/bin/python3", script, work = "/tmp", truth;
  double perturb = 0.05;
  cf_model_id model = CF_MODEL_DIELECTRIC;
  size_t max_obs = 0;
  int threads = 2, max_iterations = 100;
  bool autodiff = true, numeric = true, analytic = true, scipy = true, check = false;
};

// The common problem's data, one observation after another.
struct Data {
  cf_model_id model;
  int dim = 0, lights = 0;
  size_t count = 0;
  std::vector<uint32_t> index;
  std::vector<double> n, v, l, e, y;  // 3, 3, 3 L, 3 L, 3 per observation
  std::vector<double> lower, upper;
};

struct Outcome {
  std::string name;
  bool ran = false, skipped = false;
  std::string note;
  double seconds = 0.0, solve_seconds = 0.0, cost = NAN, solver_cost = NAN;
  int iterations = 0, evaluations = -1, jacobians = -1;
  double model_error = 0.0;  // worst relative difference from the C evaluator
  bool model_ok = true;
  std::vector<double> params;
};

// Observation i's prediction Σ_j f E_j c_i,j (3 channels) at p.
template <typename T>
void Predict(const Data &d, size_t i, const T *p, T out[3]) {
  const double *n = &d.n[3 * i], *v = &d.v[3 * i];
  out[0] = out[1] = out[2] = T(0.0);
  for (int j = 0; j < d.lights; ++j) {
    const double *l = &d.l[3 * (i * d.lights + j)], *e = &d.e[3 * (i * d.lights + j)];
    const Vec3<double> nn{n[0], n[1], n[2]}, ll{l[0], l[1], l[2]}, vv{v[0], v[1], v[2]};
    const double c_i = clayfit_jet::Dot(nn, ll);
    if (!(c_i > 0.0) || (e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0)) continue;
    T f[3] = {T(0.0), T(0.0), T(0.0)};
    clayfit_jet::Eval(d.model, p, nn, ll, vv, f);
    for (int c = 0; c < 3; ++c) out[c] += f[c] * (e[c] * c_i);
  }
}

// One observation's three residuals: the idiomatic Ceres residual block.
struct ObservationResidual {
  const Data *data;
  size_t i;
  template <typename T>
  bool operator()(const T *p, T *r) const {
    T pred[3];
    Predict(*data, i, p, pred);
    for (int c = 0; c < 3; ++c) r[c] = pred[c] - data->y[3 * i + c];
    return true;
  }
};

// One observation's three residuals with the C evaluator's analytic
// derivatives: the idiomatic Ceres layout (one residual block per
// observation, Ceres forming J) around clayfit's own model, so that the
// only difference from clayfit is the layout of the problem (clayfit hands
// Ceres each block of a thousand observations compressed to its normal
// equations, src/lsq/lsq.h).
class ObservationAnalytic final : public ceres::CostFunction {
 public:
  ObservationAnalytic(const Data *d, size_t i) : d_(d), i_(i) {
    set_num_residuals(3);
    mutable_parameter_block_sizes()->push_back(d->dim);
  }
  bool Evaluate(double const *const *parameters, double *residuals,
                double **jacobians) const override {
    const Data &d = *d_;
    const double *n = &d.n[3 * i_], *v = &d.v[3 * i_], *p = parameters[0];
    double *jacobian = jacobians != nullptr ? jacobians[0] : nullptr;
    for (int c = 0; c < 3; ++c) residuals[c] = -d.y[3 * i_ + c];
    if (jacobian != nullptr) std::fill(jacobian, jacobian + 3 * d.dim, 0.0);
    // (on the stack: Ceres calls this for every observation of every pass)
    double grad[3 * CF_MAX_DIM];
    for (int j = 0; j < d.lights; ++j) {
      const double *l = &d.l[3 * (i_ * d.lights + j)], *e = &d.e[3 * (i_ * d.lights + j)];
      const double c_i = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
      if (!(c_i > 0.0) || (e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0)) continue;
      double f[3];
      if (cf_eval(d.model, p, n, l, v, f, jacobian != nullptr ? grad : nullptr) != CF_OK)
        return false;
      for (int c = 0; c < 3; ++c) {
        residuals[c] += f[c] * (e[c] * c_i);
        if (jacobian == nullptr) continue;
        for (int k = 0; k < d.dim; ++k)
          jacobian[c * d.dim + k] += grad[c * d.dim + k] * (e[c] * c_i);
      }
    }
    return true;
  }

 private:
  const Data *d_;
  size_t i_;
};

void QuietGlog() {
  static bool done = false;
  if (!done) {
    google::InitGoogleLogging("clayfit-peers");
    FLAGS_minloglevel = google::GLOG_WARNING;
    done = true;
  }
}

enum class Derivatives { kAuto, kNumeric, kAnalytic };

template <int Dim, Derivatives How>
ceres::CostFunction *MakeCost(const Data *d, size_t i) {
  if constexpr (How == Derivatives::kAnalytic)
    return new ObservationAnalytic(d, i);
  else if constexpr (How == Derivatives::kNumeric)
    return new ceres::NumericDiffCostFunction<ObservationResidual, ceres::CENTRAL, 3, Dim>(
        new ObservationResidual{d, i});
  else
    return new ceres::AutoDiffCostFunction<ObservationResidual, 3, Dim>(
        new ObservationResidual{d, i});
}

template <int Dim, Derivatives How>
void SolveCeres(const Data &d, const std::vector<double> &start, const Options &o, Outcome *out) {
  QuietGlog();
  double t0 = peers_now();
  std::vector<double> x = start;
  ceres::Problem problem;
  for (size_t i = 0; i < d.count; ++i)
    problem.AddResidualBlock(MakeCost<Dim, How>(&d, i), nullptr, x.data());
  for (int k = 0; k < Dim; ++k) {
    problem.SetParameterLowerBound(x.data(), k, d.lower[k]);
    problem.SetParameterUpperBound(x.data(), k, d.upper[k]);
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  so.num_threads = o.threads;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = 1e-10;  // cf_lsq_default_options'
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-10;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  double t1 = peers_now();
  ceres::Solve(so, &problem, &summary);
  double t2 = peers_now();
  out->ran = true;
  out->seconds = t2 - t0;
  out->solve_seconds = t2 - t1;
  out->solver_cost = summary.final_cost;
  out->iterations = std::max(0, static_cast<int>(summary.iterations.size()) - 1);
  out->note = ceres::TerminationTypeToString(summary.termination_type);
  out->params = x;
}

template <int Dim>
void SolveCeresHow(const Data &d, const std::vector<double> &start, const Options &o,
                   Derivatives how, Outcome *out) {
  switch (how) {
    case Derivatives::kAuto:
      return SolveCeres<Dim, Derivatives::kAuto>(d, start, o, out);
    case Derivatives::kNumeric:
      return SolveCeres<Dim, Derivatives::kNumeric>(d, start, o, out);
    case Derivatives::kAnalytic:
      return SolveCeres<Dim, Derivatives::kAnalytic>(d, start, o, out);
  }
}

void SolveCeresFor(const Data &d, const std::vector<double> &start, const Options &o,
                   Derivatives how, Outcome *out) {
  if (d.model == CF_MODEL_DIELECTRIC)
    SolveCeresHow<CF_DIELECTRIC_DIM>(d, start, o, how, out);
  else
    SolveCeresHow<CF_CLAY_DIM>(d, start, o, how, out);
}

// Relative difference of a prediction from the C evaluator's, against the
// larger of its own size and 1e-6 of the largest prediction (a grazing
// pixel's prediction near 0 has no relative digits to compare).
double RelativeDifference(double a, double c, double scale) {
  return std::fabs(a - c) / std::max(std::fabs(c), 1e-6 * scale);
}

double LargestAbs(const std::vector<double> &v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::fabs(x));
  return m;
}

// The cost ½ Σ (prediction − y)² by the C evaluator.
bool CostC(const cf_capture *capture, const Data &d, const double *params, double *cost,
           cf_error *err) {
  std::vector<double> pred(3 * d.count), meas(3 * d.count);
  if (peers_predict(capture, d.model, d.index.data(), d.count, params, pred.data(), meas.data(),
                    err) != CF_OK)
    return false;
  double s = 0.0;
  for (size_t i = 0; i < pred.size(); ++i) s += (pred[i] - meas[i]) * (pred[i] - meas[i]);
  *cost = 0.5 * s;
  return true;
}

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

std::string JsonArray(const std::vector<double> &a) {
  std::string s = "[";
  char buf[40];
  for (size_t i = 0; i < a.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%.17g", i ? ", " : "", a[i]);
    s += buf;
  }
  return s + "]";
}

// One word for `sh -c`: single quotes, a ' inside written '\''.
static std::string ShellQuoted(const std::string &word) {
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
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

int Usage(FILE *f) {
  std::fprintf(f,
               "usage: clayfit-peers CAPTURE [--model M2|M4] [--max-obs N] [--json FILE]\n"
               "                     [--threads T] [--max-iterations N] [--peers LIST]\n"
               "                     [--scipy-script PATH] [--python PY] [--work DIR] [--check]\n"
               "                     [--start-from-truth TRUTH.json [--perturb D]]\n\n"
               "clayfit's fit against Ceres AutoDiff, Ceres NumericDiff (CENTRAL), Ceres with\n"
               "the C evaluator's analytic derivatives (one residual block per observation)\n"
               "and SciPy's least_squares on the same observations (issue 6). LIST: a\n"
               "comma-separated subset of autodiff,numeric,analytic,scipy (default all).\n"
               "--check: exit 1 unless every peer that ran reached clayfit's cost within %g\n"
               "relative (or better).\n"
               "Exit 1 whenever a peer's model disagrees with the C evaluator beyond %g.\n"
               "The start: the model's defaults, sigma 0.3, the albedo from a closed form;\n"
               "or (--start-from-truth) the truth clayfit synth wrote, each slot moved by D\n"
               "(default 0.05) of its range, alternately up and down (inward at a bound).\n",
               kCostTolerance, kModelTolerance);
  return f == stdout ? 0 : 2;
}

bool ParseArgs(int argc, char **argv, Options *o) {
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&](const char *what) -> const char * {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "clayfit-peers: %s needs a value\n", what);
        return nullptr;
      }
      return argv[++i];
    };
    const char *val = nullptr;
    if (a == "--model") {
      if (!(val = next("--model"))) return false;
      cf_error err = {};
      if (cf_model_find(val, &o->model, &err) != CF_OK ||
          (o->model != CF_MODEL_DIELECTRIC && o->model != CF_MODEL_CLAY)) {
        std::fprintf(stderr, "clayfit-peers: --model: M2 or M4, not '%s'\n", val);
        return false;
      }
    } else if (a == "--max-obs") {
      if (!(val = next("--max-obs"))) return false;
      o->max_obs = std::strtoull(val, nullptr, 10);
    } else if (a == "--threads") {
      if (!(val = next("--threads"))) return false;
      o->threads = std::max(1, std::atoi(val));
    } else if (a == "--max-iterations") {
      if (!(val = next("--max-iterations"))) return false;
      o->max_iterations = std::max(1, std::atoi(val));
    } else if (a == "--json") {
      if (!(val = next("--json"))) return false;
      o->json = val;
    } else if (a == "--start-from-truth") {
      if (!(val = next("--start-from-truth"))) return false;
      o->truth = val;
    } else if (a == "--perturb") {
      if (!(val = next("--perturb"))) return false;
      o->perturb = std::atof(val);
    } else if (a == "--python") {
      if (!(val = next("--python"))) return false;
      o->python = val;
    } else if (a == "--scipy-script") {
      if (!(val = next("--scipy-script"))) return false;
      o->script = val;
    } else if (a == "--work") {
      if (!(val = next("--work"))) return false;
      o->work = val;
    } else if (a == "--peers") {
      if (!(val = next("--peers"))) return false;
      std::string list = std::string(",") + val + ",";
      o->autodiff = list.find(",autodiff,") != std::string::npos;
      o->numeric = list.find(",numeric,") != std::string::npos;
      o->analytic = list.find(",analytic,") != std::string::npos;
      o->scipy = list.find(",scipy,") != std::string::npos;
    } else if (a == "--check") {
      o->check = true;
    } else if (a == "-h" || a == "--help") {
      Usage(stdout);
      std::exit(0);
    } else if (a[0] != '-' && o->capture.empty()) {
      o->capture = a;
    } else {
      std::fprintf(stderr, "clayfit-peers: unknown argument '%s'\n", a.c_str());
      return false;
    }
  }
  if (o->capture.empty()) return Usage(stderr), false;
  if (o->scipy && o->script.empty()) o->scipy = false;
  return true;
}

// The observations: lit and unclipped, all or an even subsample.
void Gather(const cf_observations *obs, const Options &o, Data *d) {
  std::vector<uint32_t> usable;
  for (size_t k = 0; k < obs->count; ++k)
    if ((obs->flags[k] & (CF_OBS_CLIPPED | CF_OBS_UNLIT)) == 0)
      usable.push_back(static_cast<uint32_t>(k));
  if (o.max_obs > 0 && o.max_obs < usable.size()) {
    for (size_t i = 0; i < o.max_obs; ++i)
      d->index.push_back(usable[i * usable.size() / o.max_obs]);
  } else {
    d->index = usable;
  }
  d->count = d->index.size();
  d->lights = obs->lights;
  const size_t L = static_cast<size_t>(obs->lights);
  for (uint32_t k : d->index) {
    d->n.insert(d->n.end(), obs->normal + 3 * k, obs->normal + 3 * k + 3);
    d->v.insert(d->v.end(), obs->view + 3 * k, obs->view + 3 * k + 3);
    d->l.insert(d->l.end(), obs->light_dir + 3 * L * k, obs->light_dir + 3 * L * (k + 1));
    d->e.insert(d->e.end(), obs->irradiance + 3 * L * k, obs->irradiance + 3 * L * (k + 1));
    d->y.insert(d->y.end(), obs->rgb + 3 * k, obs->rgb + 3 * k + 3);
  }
  const cf_model_info *m = cf_model_info_get(d->model);
  d->dim = m->dim;
  d->lower.assign(d->dim, 0.0);
  d->upper.assign(d->dim, 0.0);
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    for (int c = 0; c < info->components; ++c) {
      d->lower[m->offsets[j] + c] = info->lower;
      d->upper[m->offsets[j] + c] = info->upper;
    }
  }
}

// The start: the model's defaults with the Oren-Nayar σ at 0.3 (inside its
// range: at σ = 0 its derivative vanishes and a solver in σ never moves it)
// and the albedo from a closed form, each channel scaled to the
// measurements' least-squares projection on the prediction, in [0.02, 0.98].
bool Start(const cf_capture *capture, const Data &d, std::vector<double> *start, cf_error *err) {
  start->assign(d.dim, 0.0);
  cf_model_default_params(d.model, start->data());
  const int sigma_slot = d.model == CF_MODEL_CLAY
                             ? static_cast<int>(CF_CLAY_DIFFUSE_ROUGHNESS)
                             : static_cast<int>(CF_DIELECTRIC_DIFFUSE_ROUGHNESS);
  (*start)[sigma_slot] = 0.3;
  std::vector<double> pred(3 * d.count), meas(3 * d.count);
  if (peers_predict(capture, d.model, d.index.data(), d.count, start->data(), pred.data(),
                    meas.data(), err) != CF_OK)
    return false;
  for (int c = 0; c < 3; ++c) {
    double py = 0.0, pp = 0.0;
    for (size_t i = 0; i < d.count; ++i) {
      py += pred[3 * i + c] * meas[3 * i + c];
      pp += pred[3 * i + c] * pred[3 * i + c];
    }
    double rho = pp > 0.0 ? (*start)[c] * py / pp : (*start)[c];  // albedo is slots 0..2
    (*start)[c] = std::min(0.98, std::max(0.02, rho));
  }
  return true;
}

// The start from a truth.json (clayfit synth): slot k moved by
// perturb × its range, up for even k and down for odd k, the other way
// where that would leave the range.
bool StartFromTruth(const Data &d, const Options &o, std::vector<double> *start) {
  json_error_t jerr;
  json_t *doc = json_load_file(o.truth.c_str(), 0, &jerr);
  if (doc == nullptr) {
    std::fprintf(stderr, "clayfit-peers: %s: %s\n", o.truth.c_str(), jerr.text);
    return false;
  }
  const cf_model_info *m = cf_model_info_get(d.model);
  json_t *params = json_object_get(doc, "params");
  start->assign(d.dim, 0.0);
  bool ok = true;
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    json_t *value = json_object_get(params, info->name);
    for (int c = 0; c < info->components; ++c) {
      json_t *v = json_is_array(value) ? json_array_get(value, c) : value;
      if (!json_is_number(v)) {
        std::fprintf(stderr, "clayfit-peers: %s: params.%s: expected a number\n", o.truth.c_str(),
                     info->name);
        ok = false;
        continue;
      }
      const int k = m->offsets[j] + c;
      const double width = info->upper - info->lower, step = o.perturb * width;
      double x = json_number_value(v) + (k % 2 == 0 ? step : -step);
      if (x > info->upper || x < info->lower)
        x = json_number_value(v) - (k % 2 == 0 ? step : -step);
      (*start)[k] = std::min(info->upper - 1e-3 * width, std::max(info->lower + 1e-3 * width, x));
    }
  }
  json_decref(doc);
  return ok;
}

int Run(int argc, char **argv) {
  Options o;
  if (!ParseArgs(argc, argv, &o)) return 2;
  cf_error err = {};
  cf_capture *capture = nullptr;
  if (cf_capture_load(o.capture.c_str(), nullptr, &capture, &err) != CF_OK) {
    std::fprintf(stderr, "clayfit-peers: %s\n", err.message);
    return 1;
  }
  Data d;
  d.model = o.model;
  Gather(cf_capture_observations(capture), o, &d);
  if (d.count == 0) {
    std::fprintf(stderr, "clayfit-peers: %s has no lit, unclipped observations\n",
                 o.capture.c_str());
    cf_capture_free(capture);
    return 1;
  }
  std::vector<double> start;
  std::vector<double> pred_c(3 * d.count), meas(3 * d.count);
  if (!o.truth.empty() && !StartFromTruth(d, o, &start)) {
    cf_capture_free(capture);
    return 1;
  }
  if ((o.truth.empty() && !Start(capture, d, &start, &err)) ||
      peers_predict(capture, d.model, d.index.data(), d.count, start.data(), pred_c.data(),
                    meas.data(), &err) != CF_OK) {
    std::fprintf(stderr, "clayfit-peers: %s\n", err.message);
    cf_capture_free(capture);
    return 1;
  }
  const double scale = LargestAbs(pred_c);
  const char *code = cf_model_info_get(d.model)->code;
  std::printf(
      "clayfit-peers: %s, %s, %zu observations (lit, unclipped) x %d light slots, %d "
      "parameters, %d threads\n",
      o.capture.c_str(), code, d.count, d.lights, d.dim, o.threads);

  // The models, checked at the start before anything is timed: the
  // templated model (both Ceres peers) in double against the C evaluator.
  Outcome ref;
  ref.name = "clayfit";
  Outcome ad, nd, an, sp;
  ad.name = "ceres-autodiff";
  nd.name = "ceres-numericdiff";
  an.name = "ceres-analytic";
  sp.name = "scipy-trf";
  double templated_error = 0.0;
  for (size_t i = 0; i < d.count; ++i) {
    double p[3];
    Predict(d, i, start.data(), p);
    for (int c = 0; c < 3; ++c)
      templated_error =
          std::max(templated_error, RelativeDifference(p[c], pred_c[3 * i + c], scale));
  }
  for (Outcome *out : {&ad, &nd}) {
    out->model_error = templated_error;
    out->model_ok = templated_error <= kModelTolerance;
  }
  std::printf(
      "model check at the start: templated C++ model (Ceres peers) worst relative "
      "difference %.3g (tolerance %.0e, relative to max(|value|, 1e-6 of the largest))\n",
      templated_error, kModelTolerance);
  bool model_failed = templated_error > kModelTolerance;
  if (model_failed)
    std::fprintf(stderr, "clayfit-peers: the templated model disagrees with the C evaluator\n");

  // clayfit
  peers_clayfit_result cr;
  if (peers_clayfit_run(capture, d.model, d.index.data(), d.count, start.data(), o.threads,
                        o.max_iterations, &cr, &err) != CF_OK) {
    std::fprintf(stderr, "clayfit-peers: clayfit's solve: %s\n", err.message);
    cf_capture_free(capture);
    return 1;
  }
  ref.ran = true;
  ref.seconds = cr.seconds;
  ref.solve_seconds = cr.solve_seconds;
  ref.solver_cost = cr.cost;
  ref.iterations = cr.iterations;
  ref.params.assign(cr.params, cr.params + d.dim);
  ref.note = cr.termination;

  if (!model_failed && o.autodiff) SolveCeresFor(d, start, o, Derivatives::kAuto, &ad);
  if (!model_failed && o.numeric) SolveCeresFor(d, start, o, Derivatives::kNumeric, &nd);
  if (o.analytic) SolveCeresFor(d, start, o, Derivatives::kAnalytic, &an);
  if (o.scipy) {
    SolveScipy(d, start, pred_c, o, &sp);
    if (sp.ran)
      std::printf("model check at the start: SciPy's NumPy model worst relative difference %.3g\n",
                  sp.model_error);
    if (sp.ran && !sp.model_ok) {
      model_failed = true;
      std::fprintf(stderr,
                   "clayfit-peers: SciPy's NumPy model disagrees with the C evaluator "
                   "(%.3g)\n",
                   sp.model_error);
    }
  }

  std::vector<Outcome *> all = {&ref, &ad, &nd, &an, &sp};
  for (Outcome *out : all)
    if (out->ran && !CostC(capture, d, out->params.data(), &out->cost, &err)) {
      std::fprintf(stderr, "clayfit-peers: %s\n", err.message);
      cf_capture_free(capture);
      return 1;
    }
  cf_capture_free(capture);

  const double floor = cr.pass_seconds * cr.iterations;
  bool costs_ok = true;
  std::printf(
      "\n| contestant | wall s | iterations | final cost | relative cost difference | "
      "counts | time / clayfit's |\n|---|---|---|---|---|---|---|\n");
  std::string rows;
  for (Outcome *out : all) {
    if (!out->ran) {
      if (out != &ref && (out->skipped || !out->note.empty()))
        std::printf("| %s | skipped: %s | | | | | |\n", out->name.c_str(), out->note.c_str());
      if (out == &sp && o.scipy && !out->skipped) costs_ok = false;
      continue;
    }
    double rel = std::fabs(out->cost - ref.cost) / ref.cost;
    bool counts = rel <= kCostTolerance || out->cost < ref.cost;
    if (!counts) costs_ok = false;
    double ratio = out->seconds / ref.seconds;
    std::printf("| %s | %.3f | %d | %.10g | %.2e | %s | %.2f |\n", out->name.c_str(), out->seconds,
                out->iterations, out->cost, rel, counts ? "yes" : "no", ratio);
    char buf[2048];
    std::snprintf(
        buf, sizeof buf,
        "%s    {\"name\": \"%s\", \"seconds\": %.6g, \"solve_seconds\": %.6g, "
        "\"iterations\": %d, \"evaluations\": %d, \"cost\": %.17g, \"solver_cost\": %.17g, "
        "\"relative_cost_difference\": %.6g, \"counts\": %s, \"time_ratio\": %.6g, "
        "\"model_error\": %.6g, \"params\": %s, \"note\": ",
        rows.empty() ? "" : ",\n", out->name.c_str(), out->seconds, out->solve_seconds,
        out->iterations, out->evaluations, out->cost, out->solver_cost, rel,
        counts ? "true" : "false", ratio, out->model_error, JsonArray(out->params).c_str());
    rows += buf;
    json_t *note = json_string(out->note.c_str());
    char *dumped = json_dumps(note, JSON_ENCODE_ANY);
    rows += dumped ? dumped : "\"\"";
    rows += "}";
    std::free(dumped);
    json_decref(note);
  }
  std::printf(
      "\nthe callback's pass (value + normal equations, one thread): %.4f s, %.2f x the "
      "evaluator's",
      cr.normal_pass_seconds, cr.normal_pass_seconds / cr.pass_seconds);
  std::printf(
      "\nevaluator floor: one cf_eval_batch pass (value + gradient) over %zu pairs %.4f s x "
      "%d iterations = %.3f s; clayfit %.3f s (solve %.3f s): overhead %.2f over the floor "
      "(%.2f for the solve alone)\n",
      cr.pairs, cr.pass_seconds, cr.iterations, floor, cr.seconds, cr.solve_seconds,
      cr.seconds / floor - 1.0, cr.solve_seconds / floor - 1.0);
  std::printf(
      "tolerance: a peer counts when its final cost (by the C evaluator) is within %.0e "
      "relative of clayfit's, or lower\n",
      kCostTolerance);

  if (!o.json.empty()) {
    FILE *f = std::fopen(o.json.c_str(), "w");
    if (f == nullptr) {
      std::fprintf(stderr, "clayfit-peers: cannot write %s\n", o.json.c_str());
      return 1;
    }
    std::fprintf(
        f,
        "{\n  \"capture\": \"%s\",\n  \"model\": \"%s\",\n  \"observations\": %zu,\n  "
        "\"lights\": %d,\n  \"threads\": %d,\n  \"start\": %s,\n  \"cost_tolerance\": %g,\n  "
        "\"model_tolerance\": %g,\n  \"templated_model_error\": %.6g,\n  \"floor\": "
        "{\"pass_seconds\": %.6g, \"pairs\": %zu, \"iterations\": %d, \"seconds\": %.6g, "
        "\"clayfit_overhead\": %.6g, \"clayfit_solve_overhead\": %.6g, "
        "\"normal_pass_seconds\": %.6g},\n  \"contestants\": "
        "[\n%s\n  ]\n}\n",
        o.capture.c_str(), code, d.count, d.lights, o.threads, JsonArray(start).c_str(),
        kCostTolerance, kModelTolerance, templated_error, cr.pass_seconds, cr.pairs, cr.iterations,
        floor, cr.seconds / floor - 1.0, cr.solve_seconds / floor - 1.0, cr.normal_pass_seconds,
        rows.c_str());
    if (std::fclose(f) != 0) return 1;
  }
  if (model_failed) return 1;
  if (o.check && !costs_ok) {
    std::fprintf(stderr, "clayfit-peers: a peer did not reach clayfit's cost within %g\n",
                 kCostTolerance);
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  try {
    return Run(argc, argv);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "clayfit-peers: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "clayfit-peers: unknown exception\n");
  }
  return 1;
}
