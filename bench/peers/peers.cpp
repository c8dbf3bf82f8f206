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
// (scripts/peer_scipy.py): the contestants in peers_ceres.cpp and
// peers_scipy.cpp, this file the problem, the run and its report. Every contestant's final parameters are costed
// again by the C evaluator, so that the costs compared are one definition.
// Times are reported, never asserted. No exception escapes main.
#include <jansson.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

extern "C" {
#include "clayfit/capture.h"
#include "clayfit/model.h"
}
#include "peers.h"
#include "peers_clayfit.h"

namespace peers {
namespace {

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

// What the arguments ask for: a run, the help, or nothing (wrong ones, said
// on stderr).
enum class Parsed { kRun, kHelp, kWrong };

Parsed ParseArgs(int argc, char **argv, Options *o) {
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
      if (!(val = next("--model"))) return Parsed::kWrong;
      cf_error err = {};
      if (cf_model_find(val, &o->model, &err) != CF_OK ||
          (o->model != CF_MODEL_DIELECTRIC && o->model != CF_MODEL_CLAY)) {
        std::fprintf(stderr, "clayfit-peers: --model: M2 or M4, not '%s'\n", val);
        return Parsed::kWrong;
      }
    } else if (a == "--max-obs") {
      if (!(val = next("--max-obs"))) return Parsed::kWrong;
      o->max_obs = std::strtoull(val, nullptr, 10);
    } else if (a == "--threads") {
      if (!(val = next("--threads"))) return Parsed::kWrong;
      o->threads = std::max(1, std::atoi(val));
    } else if (a == "--max-iterations") {
      if (!(val = next("--max-iterations"))) return Parsed::kWrong;
      o->max_iterations = std::max(1, std::atoi(val));
    } else if (a == "--json") {
      if (!(val = next("--json"))) return Parsed::kWrong;
      o->json = val;
    } else if (a == "--start-from-truth") {
      if (!(val = next("--start-from-truth"))) return Parsed::kWrong;
      o->truth = val;
    } else if (a == "--perturb") {
      if (!(val = next("--perturb"))) return Parsed::kWrong;
      o->perturb = std::atof(val);
    } else if (a == "--python") {
      if (!(val = next("--python"))) return Parsed::kWrong;
      o->python = val;
    } else if (a == "--scipy-script") {
      if (!(val = next("--scipy-script"))) return Parsed::kWrong;
      o->script = val;
    } else if (a == "--work") {
      if (!(val = next("--work"))) return Parsed::kWrong;
      o->work = val;
    } else if (a == "--peers") {
      if (!(val = next("--peers"))) return Parsed::kWrong;
      std::string list = std::string(",") + val + ",";
      o->autodiff = list.find(",autodiff,") != std::string::npos;
      o->numeric = list.find(",numeric,") != std::string::npos;
      o->analytic = list.find(",analytic,") != std::string::npos;
      o->scipy = list.find(",scipy,") != std::string::npos;
    } else if (a == "--check") {
      o->check = true;
    } else if (a == "-h" || a == "--help") {
      return Parsed::kHelp;
    } else if (a[0] != '-' && o->capture.empty()) {
      o->capture = a;
    } else {
      std::fprintf(stderr, "clayfit-peers: unknown argument '%s'\n", a.c_str());
      return Parsed::kWrong;
    }
  }
  if (o->capture.empty()) return Usage(stderr), Parsed::kWrong;
  if (o->scipy && o->script.empty()) o->scipy = false;
  return Parsed::kRun;
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

// One run of the contest: the problem, the contestants' outcomes and
// clayfit's reference, from step to step of Run.
struct Contest {
  Options o;
  cf_capture *capture = nullptr;
  Data d;
  std::vector<double> start, pred_c;  // the start, the C evaluator's prediction there
  double templated_error = 0.0;       // the templated model's, at the start
  bool model_failed = false;          // a peer's model disagrees with the C evaluator
  Outcome ref, ad, nd, an, sp;
  peers_clayfit_result cr = {};

  Contest() {
    ref.name = "clayfit";
    ad.name = "ceres-autodiff";
    nd.name = "ceres-numericdiff";
    an.name = "ceres-analytic";
    sp.name = "scipy-trf";
  }
  ~Contest() {
    cf_capture_free(capture);
  }
  Contest(const Contest &) = delete;
  Contest &operator=(const Contest &) = delete;
  std::vector<Outcome *> All() {
    return {&ref, &ad, &nd, &an, &sp};
  }
};

// The capture, its observations, the start and the C evaluator's
// prediction there. False (said on stderr) when any is missing.
bool LoadProblem(Contest *t) {
  cf_error err = {};
  Data &d = t->d;
  if (cf_capture_load(t->o.capture.c_str(), nullptr, &t->capture, &err) != CF_OK) {
    std::fprintf(stderr, "clayfit-peers: %s\n", err.message);
    return false;
  }
  d.model = t->o.model;
  Gather(cf_capture_observations(t->capture), t->o, &d);
  if (d.count == 0) {
    std::fprintf(stderr, "clayfit-peers: %s has no lit, unclipped observations\n",
                 t->o.capture.c_str());
    return false;
  }
  std::vector<double> meas(3 * d.count);
  t->pred_c.assign(3 * d.count, 0.0);
  if (!t->o.truth.empty() && !StartFromTruth(d, t->o, &t->start)) return false;
  if ((t->o.truth.empty() && !Start(t->capture, d, &t->start, &err)) ||
      peers_predict(t->capture, d.model, d.index.data(), d.count, t->start.data(), t->pred_c.data(),
                    meas.data(), &err) != CF_OK) {
    std::fprintf(stderr, "clayfit-peers: %s\n", err.message);
    return false;
  }
  std::printf(
      "clayfit-peers: %s, %s, %zu observations (lit, unclipped) x %d light slots, %d "
      "parameters, %d threads\n",
      t->o.capture.c_str(), cf_model_info_get(d.model)->code, d.count, d.lights, d.dim,
      t->o.threads);
  return true;
}

// The models, checked at the start before anything is timed: the
// templated model (both Ceres peers) in double against the C evaluator.
void CheckTemplatedModel(Contest *t) {
  const double worst = TemplatedModelError(t->d, t->start.data(), t->pred_c);
  for (Outcome *out : {&t->ad, &t->nd}) {
    out->model_error = worst;
    out->model_ok = worst <= kModelTolerance;
  }
  std::printf(
      "model check at the start: templated C++ model (Ceres peers) worst relative "
      "difference %.3g (tolerance %.0e, relative to max(|value|, 1e-6 of the largest))\n",
      worst, kModelTolerance);
  t->templated_error = worst;
  t->model_failed = worst > kModelTolerance;
  if (t->model_failed)
    std::fprintf(stderr, "clayfit-peers: the templated model disagrees with the C evaluator\n");
}

// Every contestant's solve from the start: clayfit's, then the peers
// asked for (the Ceres peers over the templated model only when it
// agrees). False when clayfit's own solve fails.
bool SolveAll(Contest *t) {
  const Options &o = t->o;
  cf_error err = {};
  peers_clayfit_result &cr = t->cr;
  if (peers_clayfit_run(t->capture, t->d.model, t->d.index.data(), t->d.count, t->start.data(),
                        o.threads, o.max_iterations, &cr, &err) != CF_OK) {
    std::fprintf(stderr, "clayfit-peers: clayfit's solve: %s\n", err.message);
    return false;
  }
  t->ref.ran = true;
  t->ref.seconds = cr.seconds;
  t->ref.solve_seconds = cr.solve_seconds;
  t->ref.solver_cost = cr.cost;
  t->ref.iterations = cr.iterations;
  t->ref.params.assign(cr.params, cr.params + t->d.dim);
  t->ref.note = cr.termination;

  if (!t->model_failed && o.autodiff) SolveCeresFor(t->d, t->start, o, Derivatives::kAuto, &t->ad);
  if (!t->model_failed && o.numeric)
    SolveCeresFor(t->d, t->start, o, Derivatives::kNumeric, &t->nd);
  if (o.analytic) SolveCeresFor(t->d, t->start, o, Derivatives::kAnalytic, &t->an);
  if (!o.scipy) return true;
  SolveScipy(t->d, t->start, t->pred_c, o, &t->sp);
  if (t->sp.ran)
    std::printf("model check at the start: SciPy's NumPy model worst relative difference %.3g\n",
                t->sp.model_error);
  if (t->sp.ran && !t->sp.model_ok) {
    t->model_failed = true;
    std::fprintf(stderr,
                 "clayfit-peers: SciPy's NumPy model disagrees with the C evaluator (%.3g)\n",
                 t->sp.model_error);
  }
  return true;
}

// Every contestant's solution costed again by the C evaluator.
bool CostAll(Contest *t) {
  cf_error err = {};
  for (Outcome *out : t->All())
    if (out->ran && !CostC(t->capture, t->d, out->params.data(), &out->cost, &err)) {
      std::fprintf(stderr, "clayfit-peers: %s\n", err.message);
      return false;
    }
  return true;
}

// One contestant's row of the JSON's "contestants".
std::string JsonRow(const Outcome &out, double rel, bool counts, double ratio) {
  char buf[2048];
  std::snprintf(buf, sizeof buf,
                "    {\"name\": \"%s\", \"seconds\": %.6g, \"solve_seconds\": %.6g, "
                "\"iterations\": %d, \"evaluations\": %d, \"cost\": %.17g, \"solver_cost\": "
                "%.17g, \"relative_cost_difference\": %.6g, \"counts\": %s, \"time_ratio\": "
                "%.6g, \"model_error\": %.6g, \"params\": %s, \"note\": ",
                out.name.c_str(), out.seconds, out.solve_seconds, out.iterations, out.evaluations,
                out.cost, out.solver_cost, rel, counts ? "true" : "false", ratio, out.model_error,
                JsonArray(out.params).c_str());
  std::string row = buf;
  json_t *note = json_string(out.note.c_str());
  char *dumped = json_dumps(note, JSON_ENCODE_ANY);
  row += dumped ? dumped : "\"\"";
  row += "}";
  std::free(dumped);
  json_decref(note);
  return row;
}

// The table of contestants on stdout and their JSON rows (in *rows). True
// when every peer that ran reached clayfit's cost (and SciPy, asked for,
// ran or was skipped).
bool Report(Contest *t, std::string *rows) {
  const Outcome &ref = t->ref;
  bool costs_ok = true;
  std::printf(
      "\n| contestant | wall s | iterations | final cost | relative cost difference | "
      "counts | time / clayfit's |\n|---|---|---|---|---|---|---|\n");
  for (Outcome *out : t->All()) {
    if (!out->ran) {
      if (out != &ref && (out->skipped || !out->note.empty()))
        std::printf("| %s | skipped: %s | | | | | |\n", out->name.c_str(), out->note.c_str());
      if (out == &t->sp && t->o.scipy && !out->skipped) costs_ok = false;
      continue;
    }
    double rel = std::fabs(out->cost - ref.cost) / ref.cost;
    bool counts = rel <= kCostTolerance || out->cost < ref.cost;
    if (!counts) costs_ok = false;
    double ratio = out->seconds / ref.seconds;
    std::printf("| %s | %.3f | %d | %.10g | %.2e | %s | %.2f |\n", out->name.c_str(), out->seconds,
                out->iterations, out->cost, rel, counts ? "yes" : "no", ratio);
    *rows += (rows->empty() ? "" : ",\n") + JsonRow(*out, rel, counts, ratio);
  }
  return costs_ok;
}

// clayfit's time against the evaluator's floor (its passes times its
// iterations), on stdout.
void ReportFloor(const peers_clayfit_result &cr) {
  const double floor = cr.pass_seconds * cr.iterations;
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
}

// The run as JSON in --json's file. False when it cannot be written.
bool WriteJson(const Contest &t, const std::string &rows) {
  const Options &o = t.o;
  const peers_clayfit_result &cr = t.cr;
  const double floor = cr.pass_seconds * cr.iterations;
  FILE *f = std::fopen(o.json.c_str(), "w");
  if (f == nullptr) {
    std::fprintf(stderr, "clayfit-peers: cannot write %s\n", o.json.c_str());
    return false;
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
      o.capture.c_str(), cf_model_info_get(t.d.model)->code, t.d.count, t.d.lights, o.threads,
      JsonArray(t.start).c_str(), kCostTolerance, kModelTolerance, t.templated_error,
      cr.pass_seconds, cr.pairs, cr.iterations, floor, cr.seconds / floor - 1.0,
      cr.solve_seconds / floor - 1.0, cr.normal_pass_seconds, rows.c_str());
  return std::fclose(f) == 0;
}

// The exit status: 0, 1 (a failure, a model that disagrees or, with
// --check, a peer short of clayfit's cost) or 2 (the arguments).
int Run(int argc, char **argv) {
  Contest t;
  switch (ParseArgs(argc, argv, &t.o)) {
    case Parsed::kHelp:
      return Usage(stdout);
    case Parsed::kWrong:
      return 2;
    case Parsed::kRun:
      break;
  }
  if (!LoadProblem(&t)) return 1;
  CheckTemplatedModel(&t);
  if (!SolveAll(&t) || !CostAll(&t)) return 1;
  cf_capture_free(t.capture);
  t.capture = nullptr;
  std::string rows;
  const bool costs_ok = Report(&t, &rows);
  ReportFloor(t.cr);
  if (!t.o.json.empty() && !WriteJson(t, rows)) return 1;
  if (t.model_failed) return 1;
  if (t.o.check && !costs_ok) {
    std::fprintf(stderr, "clayfit-peers: a peer did not reach clayfit's cost within %g\n",
                 kCostTolerance);
    return 1;
  }
  return 0;
}

}  // namespace
}  // namespace peers

int main(int argc, char **argv) {
  try {
    return peers::Run(argc, argv);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "clayfit-peers: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "clayfit-peers: unknown exception\n");
  }
  return 1;
}
