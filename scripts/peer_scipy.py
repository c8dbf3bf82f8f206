#!/usr/bin/env python3
"""The SciPy peer of clayfit-peers (issue 6): what a researcher would write
instead of clayfit. M2 (dielectric) and M4 (clay) of docs/model.md, vectorised in
NumPy over every observation, fitted by scipy.optimize.least_squares
(method 'trf', bounds, the default 2-point finite-difference Jacobian).

usage: peer_scipy.py DIR

DIR holds what clayfit-peers wrote: normal.npy, view.npy (N x 3),
light.npy, irradiance.npy (N x L x 3), measured.npy (N x 3), prediction_c.npy
(the C evaluator's prediction at the start, N x 3) and problem.json (model,
start, lower, upper, ftol, xtol, gtol). Prints one JSON object: the model
check (worst relative difference from the C evaluator at the start), the
solve's wall time (without Python's start-up and the file loading), the
final cost (1/2 sum r^2), nfev, njev, x and SciPy's message; or
{"skipped": why} when NumPy or SciPy is missing.
"""
import json
import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "2")  # the benchmark's 2 threads
os.environ.setdefault("OPENBLAS_NUM_THREADS", "2")

try:
    import numpy as np
    from scipy.optimize import least_squares
except ImportError as e:  # python3-numpy / python3-scipy not installed
    print(json.dumps({"skipped": "no SciPy: %s" % e}))
    sys.exit(0)

DBL_MIN = np.finfo(float).tiny


def dot(a, b):
    return np.einsum("...k,...k->...", a, b)


def fresnel(f0, c):
    """The exact dielectric Fresnel from eta (docs/model.md (8), model version 2;
    Walter et al. 2007 eq. 22); F = 0 at F0 = 0."""
    c = np.clip(c, 0.0, 1.0)
    if f0 <= 0.0:
        return np.zeros_like(c)
    sq = np.sqrt(f0)
    g = np.sqrt(4.0 * sq / ((1.0 - sq) * (1.0 - sq)) + c * c)
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return 0.5 * a * a * (1.0 + b * b)


def fresnel_mean(eta):
    """Its cosine-weighted hemispherical mean for light from outside, closed
    form (docs/model.md (27)), eta > 1."""
    e2, e4 = eta * eta, eta**4
    return (0.5 + (eta - 1.0) * (3.0 * eta + 1.0) / (6.0 * (eta + 1.0) ** 2)
            + e2 * (e2 - 1.0) ** 2 / (e2 + 1.0) ** 3 * np.log((eta - 1.0) / (eta + 1.0))
            - 2.0 * e2 * eta * (e2 + 2.0 * eta - 1.0) / ((e2 + 1.0) * (e4 - 1.0))
            + 8.0 * e4 * (e4 + 1.0) / ((e2 + 1.0) * (e4 - 1.0) ** 2) * np.log(eta))


def ggx_d(alpha, c_h):
    a2 = alpha * alpha
    q = (a2 - 1.0) * c_h * c_h + 1.0
    return a2 / (np.pi * q * q)


def smith_v(alpha, c_i, c_o):
    a2 = alpha * alpha
    return 0.5 / (c_o * np.sqrt(c_i * c_i * (1.0 - a2) + a2) + c_i * np.sqrt(c_o * c_o * (1.0 - a2) + a2))


def specular(f0, r, n, l, v):
    s = l + v
    length = np.sqrt(dot(s, s))
    h = s / length[..., None]
    return fresnel(f0, length / 2.0) * ggx_d(r * r, dot(n, h)) * smith_v(r * r, dot(n, l), dot(n, v))


def oren_nayar_factor(sigma, n, l, v):
    """A + B max(0, g)/max(c_i, c_o): ON = rho/pi times this."""
    s2 = sigma * sigma
    a = 1.0 - 0.5 * s2 / (s2 + 0.33)
    b = 0.45 * s2 / (s2 + 0.09)
    c_i, c_o = dot(n, l), dot(n, v)
    g = dot(l, v) - c_i * c_o
    angular = np.where(g > 0.0, g / np.maximum(c_i, c_o), 0.0)
    return a + b * angular


def dielectric(p, n, l, v):
    """M2 at every (n, l, v): N x 3."""
    rho, sigma, r, f0 = p[0:3], p[3], p[4], p[5]
    c_i, c_o = dot(n, l), dot(n, v)
    spec = specular(f0, r, n, l, v)
    trans = (1.0 - fresnel(f0, c_i)) * (1.0 - fresnel(f0, c_o))
    on = oren_nayar_factor(sigma, n, l, v)
    return spec[:, None] + (trans * on)[:, None] * rho[None, :] / np.pi


def clay(p, n, l, v):
    """M4 (docs/model.md §3.5, steps 1-8) at every (n, l, v): N x 3."""
    rho, sigma, r1, f0_1 = p[0:3], p[3], p[4], p[5]
    tau, r2, f0_2 = p[6:9], p[9], p[10]
    c_i, c_o = dot(n, l), dot(n, v)
    top = specular(f0_1, r1, n, l, v)
    sq = np.sqrt(f0_1)
    eta = (1.0 + sq) / (1.0 - sq)
    eta2_m1 = 4.0 * sq / ((1.0 - sq) * (1.0 - sq))
    c_ip = np.sqrt(eta2_m1 + c_i * c_i) / eta
    c_op = np.sqrt(eta2_m1 + c_o * c_o) / eta
    lp = (l - c_i[:, None] * n) / eta + c_ip[:, None] * n
    vp = (v - c_o[:, None] * n) / eta + c_op[:, None] * n
    trans = (1.0 - fresnel(f0_1, c_i)) * (1.0 - fresnel(f0_1, c_o))
    fbar_e = fresnel_mean(eta)
    fbar_i = 1.0 - (1.0 - fbar_e) / (eta * eta)
    base_spec = specular(f0_2, r2, n, lp, vp)
    base_trans = (1.0 - fresnel(f0_2, c_ip)) * (1.0 - fresnel(f0_2, c_op))
    on = oren_nayar_factor(sigma, n, lp, vp)
    absorption = np.exp(-tau[None, :] * (1.0 / c_ip + 1.0 / c_op)[:, None])
    k = 1.0 / (1.0 - rho * fbar_i * np.exp(-4.0 * tau))
    base = base_spec[:, None] + (k * rho / np.pi)[None, :] * (base_trans * on)[:, None]
    return top[:, None] + (trans / (eta * eta))[:, None] * absorption * base


MODELS = {"M2": dielectric, "M4": clay}


def make_predict(model, n, v, lights, irradiance):
    """prediction(p): sum over light slots of f E c_i, N x 3, f = 0 where
    the pair is not lit and seen."""
    brdf = MODELS[model]
    slots = []
    for j in range(lights.shape[1]):
        l = lights[:, j, :]
        e = irradiance[:, j, :]
        c_i, c_o = dot(n, l), dot(n, v)
        lit = (c_i > 0.0) & (c_o > 0.0) & (c_i * c_o >= DBL_MIN) & np.any(e != 0.0, axis=1)
        idx = np.nonzero(lit)[0]
        slots.append((idx, n[idx], l[idx], v[idx], e[idx] * c_i[idx, None]))

    def predict(p):
        out = np.zeros((n.shape[0], 3))
        for idx, nn, ll, vv, w in slots:
            out[idx] += brdf(p, nn, ll, vv) * w
        return out

    return predict


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    d = sys.argv[1]
    with open(os.path.join(d, "problem.json")) as f:
        problem = json.load(f)
    n = np.load(os.path.join(d, "normal.npy"))
    v = np.load(os.path.join(d, "view.npy"))
    lights = np.load(os.path.join(d, "light.npy"))
    irradiance = np.load(os.path.join(d, "irradiance.npy"))
    y = np.load(os.path.join(d, "measured.npy"))
    pred_c = np.load(os.path.join(d, "prediction_c.npy"))
    x0 = np.array(problem["start"])
    lower, upper = np.array(problem["lower"]), np.array(problem["upper"])

    predict = make_predict(problem["model"], n, v, lights, irradiance)
    # the model check: the C evaluator's prediction at the start
    p0 = predict(x0)
    scale = np.max(np.abs(pred_c))
    model_error = float(np.max(np.abs(p0 - pred_c) / np.maximum(np.abs(pred_c), 1e-6 * scale)))

    def residuals(p):
        return (predict(p) - y).ravel()

    t0 = time.perf_counter()
    result = least_squares(residuals, x0, bounds=(lower, upper), method="trf",
                           ftol=problem["ftol"], xtol=problem["xtol"], gtol=problem["gtol"])
    seconds = time.perf_counter() - t0
    print(json.dumps({
        "model_error": model_error,
        "seconds": seconds,
        "cost": float(result.cost),
        "nfev": int(result.nfev),
        "njev": int(result.njev) if result.njev is not None else None,
        "x": [float(t) for t in result.x],
        "status": int(result.status),
        "message": result.message,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
