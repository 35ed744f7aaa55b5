#!/usr/bin/python3
"""Coefficients of pikg-gen's vector erfc (compiler/pik_gen/backends/vmath.py).

erfcx(a) = exp(a^2) erfc(a) = K/(a + K) Q(t), t = (a - K)/(a + K), on [0, a_max].
Q is the Chebyshev interpolant (degree DEG, at DEG + 1 Chebyshev points of t,
values at 50 digits with mpmath) re-expanded in powers of t and rounded to the
working precision; the script then measures the relative error of erfcx computed
as the generated code does (d = 1/(a+K), t = 1 - 2K d, Horner, K d Q) on 4000
points of [0, a_max] and 200 points of [1e-8, 1] and prints it in ulp.

  /usr/bin/python3 compiler/tools/fit_erfcx.py 2 24 28 d     # F64
  /usr/bin/python3 compiler/tools/fit_erfcx.py 2 9 10.5 f    # F32
"""
import sys

import mpmath as mp
import numpy as np

mp.mp.dps = 50


def main() -> None:
    K, deg, amax = mp.mpf(sys.argv[1]), int(sys.argv[2]), mp.mpf(sys.argv[3])
    dt = np.float64 if sys.argv[4] == "d" else np.float32
    tmin, tmax = mp.mpf(-1), (amax - K) / (amax + K)
    mid, half = (tmax + tmin) / 2, (tmax - tmin) / 2

    def q_of_t(t):
        a = K * (1 + t) / (1 - t)
        return mp.erfc(a) * mp.exp(a * a) * (a + K) / K

    n = deg + 1
    nodes = [mp.cos(mp.pi * (k + mp.mpf(1) / 2) / n) for k in range(n)]
    vals = [q_of_t(mid + half * s) for s in nodes]
    cheb = [2 * mp.fsum(vals[k] * mp.cos(j * mp.pi * (k + mp.mpf(1) / 2) / n) for k in range(n)) / n
            for j in range(n)]
    cheb[0] /= 2
    # T_j(s) with s = (t - mid)/half, as polynomials in t
    s_poly = [-mid / half, 1 / half]

    def mul(p, q):
        r = [mp.mpf(0)] * (len(p) + len(q) - 1)
        for i, x in enumerate(p):
            for j, y in enumerate(q):
                r[i + j] += x * y
        return r

    def add(p, q):
        m = max(len(p), len(q))
        return [(p[i] if i < len(p) else 0) + (q[i] if i < len(q) else 0) for i in range(m)]

    T = [[mp.mpf(1)], s_poly]
    for _ in range(2, n):
        T.append(add(mul([2 * x for x in s_poly], T[-1]), [-x for x in T[-2]]))
    mono = [mp.mpf(0)] * n
    for j in range(n):
        for i, x in enumerate(T[j]):
            mono[i] += cheb[j] * x
    coefs = [dt(float(m)) for m in mono]
    print("(" + ", ".join(repr(float(c)) for c in coefs) + ")")
    Kd, worst, where = dt(float(K)), 0.0, 0.0
    for a in np.concatenate([np.linspace(0, float(amax), 4001), np.geomspace(1e-8, 1, 200)]):
        a = dt(a)
        d = dt(1) / (a + Kd)
        t = dt(dt(1) - dt(2) * Kd * d)
        q = dt(0)
        for c in coefs[::-1]:
            q = dt(q * t + c)
        v = dt(dt(Kd * d) * q)
        A = mp.mpf(float(a))
        e = abs(mp.mpf(float(v)) / (mp.erfc(A) * mp.exp(A * A)) - 1)
        if e > worst:
            worst, where = float(e), float(a)
    print(f"max relative error of erfcx: {worst / np.finfo(dt).eps:.2f} ulp at a = {where}")


if __name__ == "__main__":
    main()
