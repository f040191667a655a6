#!/usr/bin/env python3
"""Independent check of rows of tukey_reference.csv with mpmath (Debian python3-mpmath):
nested tanh-sinh quadrature (mp.quad) at 30 digits, a different method and different code
from tukey_reference.cpp.

    python3 tests/data/stats/tukey_check.py ROW [ROW ...]   (0-based data rows; ~1-5 min each)

Prints each row's value, mpmath's, and their relative difference.
"""
import csv
import os
import sys

import mpmath as mp


def U(w, k):
    m = k - 1

    def f(z):
        a = mp.ncdf(z)
        b = mp.ncdf(z - w)
        d = a - b
        s, dp = mp.mpf(1), mp.mpf(1)
        for _ in range(1, m):
            dp *= d
            s = a * s + dp
        return k * mp.npdf(z) * b * s

    return mp.quad(f, sorted(set([-mp.inf, mp.mpf(0), w / 2, w, mp.inf])))


def upper(q, k, df):
    q = mp.mpf(q)
    if df == "Inf":
        return U(q, k)
    nu = mp.mpf(df)
    logc = nu / 2 * mp.log(nu) - mp.loggamma(nu / 2) - (nu / 2 - 1) * mp.log(2)

    def g(s):
        if s == 0:
            return mp.mpf(0)
        return mp.exp(logc + (nu - 1) * mp.log(s) - nu * s * s / 2) * U(q * s, k)

    mode = mp.sqrt((nu - 1) / nu)
    pts = sorted(set([mp.mpf(0), 1 / q, 3 / q, 6 / q, 12 / q, mode, mp.mpf(2), mp.inf]))
    return mp.quad(g, pts)


def main():
    mp.mp.dps = 30
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "tukey_reference.csv")
    rows = list(csv.DictReader(open(path)))
    for i in map(int, sys.argv[1:]):
        r = rows[i]
        ref = mp.mpf(r["upper"])
        got = upper(r["q"], int(r["k"]), r["df"])
        print(f"row {i}: k={r['k']} df={r['df']} q={r['q']}: csv {mp.nstr(ref, 20)} mpmath {mp.nstr(got, 20)} "
              f"rel diff {mp.nstr(abs(got - ref) / ref, 3)}", flush=True)


if __name__ == "__main__":
    main()
