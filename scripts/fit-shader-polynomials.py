#!/usr/bin/env python3
"""Refits the polynomials in src/gpu/core/approx_constants.rs (needs numpy; not run by the build).

Least squares at Chebyshev nodes, reweighted towards the minimax error; prints the
coefficients (lowest power first) and the largest error of an f32 evaluation.
"""
import numpy as np

P = np.polynomial.polynomial


def fit(f, lo, hi, deg, relative, n=4000):
    x = np.cos(np.pi * (np.arange(n) + 0.5) / n) * (hi - lo) / 2 + (hi + lo) / 2
    y = f(x)
    w = 1 / np.abs(y) if relative else np.ones_like(y)
    for _ in range(30):
        c = P.polyfit(x, y, deg, w=w)
        e = (P.polyval(x, c) - y) / (np.abs(y) if relative else 1)
        w = w * (1 + 2 * np.abs(e) / np.abs(e).max())
    return c


def horner32(c, x):
    r = np.float32(c[-1])
    for k in c[-2::-1]:
        r = (r * x + np.float32(k)).astype(np.float32)
    return r


decode = fit(lambda v: ((v + 0.055) / 1.055) ** 2.4, 0.04045, 1.0, 8, relative=True)
codes = np.arange(11, 256)
exact = ((codes / 255 + 0.055) / 1.055) ** 2.4
got = horner32(decode, (codes / np.float32(255)).astype(np.float32))
print("SRGB_DECODE_POLY", list(decode), "max relative error", np.abs(got / exact - 1).max())

encode = fit(lambda q: q ** (5 / 3), 0.0031308 ** 0.25, 1.0, 5, relative=False)
v = np.geomspace(0.0031308, 1, 100000).astype(np.float32)
got = np.float32(1.055) * horner32(encode, np.sqrt(np.sqrt(v))) - np.float32(0.055)
err = 255 * np.abs(got - (1.055 * v.astype(np.float64) ** (1 / 2.4) - 0.055)).max()
print("SRGB_ENCODE_POLY", list(encode), "max error in 8-bit codes", err)
