#!/usr/bin/env python3
"""High-precision reference values of the studentized range upper tail P(Q > q; k, df).

Writes tukey_reference.csv (columns k, df, q, upper, lower, digits) for
tests/stats/tukey_accuracy_test.cpp. Method: mpmath (Debian's python3-mpmath) at 30
significant digits,

    P(Q > q) = int_0^inf f_df(s) U(q s) ds,
    U(w) = k int phi(z) Phi(z - w) sum_j Phi(z)^j (Phi(z) - Phi(z - w))^(k-2-j) dz,

(the integrand of 1 - W(w) written without cancellation, so tiny tails keep their digits),
f_df the density of sqrt(chi2_df / df), by composite Gauss-Legendre on panels sized to both
scales of the outer integrand (the chi density's width 1/sqrt(2 df) and the range tail's
1/q). Every value is computed twice (10 and 14 nodes per panel) and kept only when the two
agree to 1e-18 relative; 'digits' records the agreement. q is chosen (by a double-precision
version of the same integral, then rounded to 6 significant digits) so that the upper tail
is near the targets in TARGETS; the stored q is exact and the reference is for that q.

Run: python3 tests/data/stats/tukey_reference.py > tests/data/stats/tukey_reference.csv
(about 40 min on one core).
"""
import math
import sys

import mpmath as mp

KS = [2, 3, 5, 10, 20]
DFS = [2, 3, 7, 30, "inf"]
TARGETS = [0.5, 1e-3, 1e-8, 1e-15]
EXTRA_DF = [(20, 120), (3, 1000)]
EXTRA = [(10, 7, "27.7407")]  # the case issue #24 reported


def gl_nodes(n):
    xs, ws = [], []
    for i in range(1, n + 1):
        x = mp.cos(mp.pi * (i - mp.mpf(1) / 4) / (n + mp.mpf(1) / 2))
        for _ in range(100):
            p0, p1 = mp.mpf(1), x
            for j in range(2, n + 1):
                p0, p1 = p1, ((2 * j - 1) * x * p1 - (j - 1) * p0) / j
            dp = n * (x * p1 - p0) / (x * x - 1)
            dx = p1 / dp
            x -= dx
            if abs(dx) < mp.mpf(10) ** (-mp.mp.dps - 3):
                break
        p0, p1 = mp.mpf(1), x
        for j in range(2, n + 1):
            p0, p1 = p1, ((2 * j - 1) * x * p1 - (j - 1) * p0) / j
        dp = n * (x * p1 - p0) / (x * x - 1)
        xs.append(x)
        ws.append(2 / ((1 - x * x) * dp * dp))
    return xs, ws


class Num:
    """The same integral in a number system: mpmath (M) or Python floats (F)."""

    def __init__(self, high, nodes):
        self.high = high
        if high:
            self.nodes = gl_nodes(nodes)
            self.f = mp.mpf
            self.ncdf, self.npdf, self.exp, self.log = mp.ncdf, mp.npdf, mp.exp, mp.log
            self.lgamma = mp.loggamma
            self.fsum = mp.fsum
        else:
            mp.mp.dps, saved = 20, mp.mp.dps
            xs, ws = gl_nodes(nodes)
            mp.mp.dps = saved
            self.nodes = ([float(x) for x in xs], [float(w) for w in ws])
            self.f = float
            self.ncdf = lambda x: 0.5 * math.erfc(-x / math.sqrt(2))
            self.npdf = lambda x: math.exp(-0.5 * x * x) / math.sqrt(2 * math.pi)
            self.exp, self.log, self.lgamma, self.fsum = math.exp, math.log, math.lgamma, math.fsum

    def panels(self, g, a, b, n):
        xs, ws = self.nodes
        tot = []
        for i in range(n):
            lo = a + (b - a) * i / n
            hi = a + (b - a) * (i + 1) / n
            h, c = (hi - lo) / 2, (hi + lo) / 2
            tot.append(h * self.fsum(w * g(c + h * x) for x, w in zip(xs, ws)))
        return self.fsum(tot)

    def U(self, w, k):
        m = k - 1

        def g(z):
            a = self.ncdf(z)
            b = self.ncdf(z - w)
            d = a - b
            s, ap = self.f(0), self.f(1)
            for j in range(m):
                s += ap * d ** (m - 1 - j)
                ap *= a
            return k * self.npdf(z) * b * s

        zw = 11 if self.high else 9  # phi(11) ~ 1e-27, phi(9) ~ 1e-18
        lo, hi = min(-zw, w / 2 - zw), max(zw, w / 2 + zw)
        return self.panels(g, self.f(lo), self.f(hi), int(math.ceil((hi - lo) / 1.5)))

    def upper(self, q, k, df):
        q = self.f(q)
        if df == "inf":
            return self.U(q, k)
        nu = self.f(df)
        logc = nu / 2 * self.log(nu) - self.lgamma(nu / 2) - (nu / 2 - 1) * self.log(self.f(2))

        def g(s):
            if s <= 0:
                return self.f(0)
            return self.exp(logc + (nu - 1) * self.log(s) - nu * s * s / 2) * self.U(q * s, k)

        # The chi density is < 1e-48 of its peak beyond smax; U(q s) < 1e-100 beyond 30 / q.
        smax = 1.0
        while (df - 1) * math.log(smax) - df * smax * smax / 2 > -110:
            smax *= 1.1
        send = min(smax, 30 / float(q))
        h = min(2 / float(q), 0.5 / math.sqrt(2 * df), 0.25)
        return self.panels(g, self.f(0), self.f(send), max(6, int(math.ceil(send / h))))


def find_q(num, k, df, target):
    lo, hi = 0.0, 1.0
    while num.upper(hi, k, df) > target:
        lo, hi = hi, hi * 2
    llo, lhi = math.log(max(lo, 1e-3)), math.log(hi)
    for _ in range(40):
        mid = 0.5 * (llo + lhi)
        if num.upper(math.exp(mid), k, df) > target:
            llo = mid
        else:
            lhi = mid
        if lhi - llo < 1e-7:
            break
    return float(f"{math.exp(0.5 * (llo + lhi)):.6g}")


def main():
    fl = Num(False, 10)
    points = []
    for k in KS:
        for df in DFS:
            for t in TARGETS:
                points.append((k, df, repr(find_q(fl, k, df, t))))
    for k, df in EXTRA_DF:
        for t in TARGETS:
            points.append((k, df, repr(find_q(fl, k, df, t))))
    points += EXTRA
    mp.mp.dps = 25
    a, b = Num(True, 10), Num(True, 14)
    print("k,df,q,upper,lower,digits")
    for k, df, q in points:
        ua, ub = a.upper(mp.mpf(q), k, df), b.upper(mp.mpf(q), k, df)
        agree = abs(ua - ub) / ub
        digits = int(min(25, -mp.log10(agree))) if agree > 0 else 25
        if digits < 18:
            print(f"# k={k} df={df} q={q}: only {digits} digits, skipped", file=sys.stderr)
            continue
        print(f"{k},{df if df != 'inf' else 'Inf'},{q},{mp.nstr(ub, 25)},{mp.nstr(1 - ub, 25)},{digits}", flush=True)


if __name__ == "__main__":
    main()
