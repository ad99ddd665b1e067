#!/usr/bin/env python3
"""Lenth's PSE, ME and SME for the FrF2 8-3.1 oracle design, computed as FrF2/DoE.base do.

FrF2's DanielPlot and DoE.base's halfnormal/ME.Lenth take the effects 2 x coef(lm(y ~ model))
without the intercept, dropping the coefficients lm reports as NA (a column that is a linear
combination of earlier columns in formula order: R's pivoted QR). Lenth (1989), Technometrics
31:469-473: s0 = 1.5 median|c|, PSE = 1.5 median{|c| : |c| < 2.5 s0}, ME = t(0.975, m/3) PSE,
SME = t(gamma, m/3) PSE, gamma = (1 + 0.95^(1/m)) / 2, m the number of effects.

Pure Python (no numpy, no R on the machine that made the numbers): least squares by modified
Gram-Schmidt in formula order, the Student t quantile by Simpson integration of the density and
bisection -- independent of demcal's incomplete-beta code. Output: expected.txt.
"""
import csv, itertools, math, os

HERE = os.path.dirname(os.path.abspath(__file__))


def read_design():
    with open(os.path.join(HERE, "..", "doe-oracle", "frf2_32run_8fac_design_standard_order.csv")) as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(v) for v in r] for r in rows[1:]]


def read_response():
    with open(os.path.join(HERE, "response.csv")) as f:
        return [float(r[0]) for r in list(csv.reader(f))[1:]]


def lm_effects(columns, y):
    """2 x coefficients of the non-aliased columns (formula order), by Gram-Schmidt."""
    n = len(y)
    basis, kept = [[1.0 / math.sqrt(n)] * n], []
    for name, col in columns:
        v = col[:]
        for _ in range(2):
            for q in basis:
                d = sum(a * b for a, b in zip(v, q))
                v = [a - d * b for a, b in zip(v, q)]
        norm = math.sqrt(sum(a * a for a in v))
        if norm <= 1e-9 * math.sqrt(sum(a * a for a in col)):
            continue  # NA in R
        basis.append([a / norm for a in v])
        kept.append((name, col))
    # On an orthogonal two-level design the kept columns are orthogonal: coef = x'y / x'x.
    return [(name, 2.0 * sum(a * b for a, b in zip(col, y)) / sum(a * a for a in col))
            for name, col in kept]


def t_cdf(x, df, steps=20000):
    c = math.exp(math.lgamma((df + 1) / 2) - math.lgamma(df / 2)) / math.sqrt(df * math.pi)
    f = lambda t: c * (1 + t * t / df) ** (-(df + 1) / 2)
    h = x / steps
    s = f(0) + f(x) + sum((4 if i % 2 else 2) * f(i * h) for i in range(1, steps))
    return 0.5 + s * h / 3


def t_quantile(p, df):
    lo, hi = 0.0, 1.0
    while t_cdf(hi, df) < p:
        hi *= 2
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if t_cdf(mid, df) < p else (lo, mid)
    return 0.5 * (lo + hi)


def median(v):
    v = sorted(v)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def lenth(effects, alpha=0.05):
    a = [abs(e) for e in effects]
    s0 = 1.5 * median(a)
    pse = 1.5 * median([x for x in a if x < 2.5 * s0])
    m = len(a)
    gamma = 0.5 * (1 + (1 - alpha) ** (1.0 / m))
    return m, pse, t_quantile(1 - alpha / 2, m / 3) * pse, t_quantile(gamma, m / 3) * pse


def main():
    names, x = read_design()
    y = read_response()
    col = lambda idx: [math.prod(r[i] for i in idx) for r in x]
    mains = [(names[i], col([i])) for i in range(len(names))]
    fi2 = [(names[i] + ":" + names[j], col([i, j]))
           for i, j in itertools.combinations(range(len(names)), 2)]
    with open(os.path.join(HERE, "expected.txt"), "w") as out:
        out.write("# model m PSE ME SME (alpha 0.05), from lenth_oracle.py\n")
        for model, columns in (("main", mains), ("2fi", mains + fi2)):
            m, pse, me, sme = lenth([e for _, e in lm_effects(columns, y)])
            out.write(f"{model} {m} {pse:.12g} {me:.12g} {sme:.12g}\n")


if __name__ == "__main__":
    main()
