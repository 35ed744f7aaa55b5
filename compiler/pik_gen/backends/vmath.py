"""Vector `exp` and `erfc` for the SIMD backends, written once over an ISA's hooks.

Both are built from the ISA's operation table (add, sub, mul, madd, nmadd, div,
min, max, abs) and three small hooks every SIMD ISA provides (`vround`: nearest
integer; `vpow2`: 2^n for a float vector of integers n, |n| <= 600 (F64) or 75
(F32), by shifting n + bias into the exponent field; `select_negative`: a where
x has its sign bit set, else b). They run on all lanes, no branch, no table.

exp(x) (Cody & Waite 1980, Software Manual for the Elementary Functions, ch. 6)
---------------------------------------------------------------------------
  x is clamped to [lo, hi] (NaN passes: std::max(x, lo) and std::min(.., hi)
  return x when x is NaN); n = nearest(x / ln 2); r = x - n ln2_hi - n ln2_lo
  (ln2_hi has its low mantissa bits cleared, so n ln2_hi is exact, and the
  subtraction is exact: |r| <= ln2/2 + 1 ulp); p = the Taylor polynomial of
  e^r (degree 13 for F64, truncation < 4.3e-18 relative; degree 7 for F32,
  < 5.3e-9) by Horner's rule; exp(x) = (p 2^n1) 2^n2 with n1 = nearest(n/2),
  n2 = n - n1, so 2^n1 and 2^n2 are normal numbers for every n of the
  clamped range and the result, rounded once, overflows to inf above
  log(max) and is subnormal or 0 below log(min normal), as std::exp.
  lo and hi lie past the under- and overflow thresholds (F64 -746 / 710:
  exp(-746) < min subnormal / 2 rounds to 0, exp(709.79) is inf; F32 -104 / 88.8).
  Measured error (tests/compiler/test_vmath.py, against long double on 10^5
  points and the edges): F64 <= 1 ulp, F32 <= 1 ulp.

erfc(x)
-------
  erfc(x) = exp(-x^2) erfcx(x) for x >= 0, and 2 - erfc(-x) for x < 0.
  erfcx(a) = exp(a^2) erfc(a) is smooth and bounded on [0, inf) and is
  approximated, after Schonfelder (1978, Math. Comp. 32, 1232), in the variable
  t = (a - K)/(a + K), K = 2, which maps [0, a_max] onto [-1, (a_max-K)/(a_max+K)]:
      erfcx(a) = K/(a + K) * Q(t),   Q a polynomial (degree 24 for F64, 9 for F32)
  whose coefficients are the Chebyshev interpolant of (a+K)/K erfcx(a) in t
  (values at 50 digits), re-expanded in powers of t and rounded
  (compiler/tools/fit_erfcx.py prints them; max error of erfcx over the range:
  F64 1.8 ulp, F32 2.1 ulp with the rounding of t). One division d = 1/(a+K)
  gives both t = 1 - 2K d and K/(a+K) = K d. exp(-a^2) takes the rounding of
  a^2 into account (a^2 = h + l exactly, l by an FMA; exp(-a^2) = exp(-h)(1 - l)),
  so the relative error stays a few ulp up to the underflow of erfc
  (a_max = 28 for F64, where erfc is 0; 10.5 for F32). No cancellation
  anywhere: for x < 0, 2 - erfc(|x|) is in [1, 2].
  Measured error: F64 <= 4 ulp, F32 <= 3 ulp (relative, normal results;
  absolute 2 subnormal units where erfc(x) is subnormal).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from pik_gen.ir.nodes import fresh_name
from pik_gen.types import Scalar, Type

if TYPE_CHECKING:
    from pik_gen.backends.simd import EmitState, Let, Simd

S = Scalar

# (lo, hi, ln2_hi, ln2_lo, Taylor degree)
EXP = {
    S.F64: (-746.0, 710.0, 0.6931467056274414, 4.7493250390316726e-07, 13),
    S.F32: (-104.0, 88.8, 0.693115234375, 3.194618329871446e-05, 7),
}
LOG2E = 1.4426950408889634

ERFCX_K = 2.0
ERFC_AMAX = {S.F64: 28.0, S.F32: 10.5}
# Q(t), constant term first (compiler/tools/fit_erfcx.py 2 24 28 d / 2 9 10.5 f)
ERFCX_Q = {
    S.F64: (0.5107913526210115, -0.34358034220690536, 0.1397360462780236, -0.018221115753430276,
            -0.01075533094452084, 0.003239592533521941, 0.0015453060244376253, -0.0004186480252833648,
            -0.00033153669034060673, 1.718566173749668e-05, 7.223492391389934e-05, 1.707477121455408e-05,
            -1.0845998080139768e-05, -8.061626648497283e-06, -5.695328911356867e-07, 1.8245577755819384e-06,
            1.016029076484496e-06, -2.5756567964739325e-09, -3.090483385124264e-07, -1.6000721639294473e-07,
            2.3120013934296395e-08, 5.604123098681145e-08, 1.2053848057593199e-08, -7.483386373386363e-09,
            -2.9492003898066746e-09),
    S.F32: (0.5107913613319397, -0.3435804843902588, 0.13973626494407654, -0.0182175412774086,
            -0.010756121948361397, 0.0032144675496965647, 0.0015354793285951018, -0.0003531239344738424,
            -0.0002777678600978106, -3.410497811273672e-05),
}


def _kind(s: Scalar) -> Scalar:
    return S.F64 if s == S.F64 else S.F32


class Builder:
    """Emits `Let` steps of one vector function from the ISA's table and hooks."""

    def __init__(self, isa: "Simd", st: "EmitState", s: Scalar, out: str) -> None:
        from pik_gen.backends.simd import Let
        self.isa, self.st, self.s, self.out = isa, st, s, out
        self.T = isa.vtype(st, Type(s))
        self.lets: list[Let] = []
        self._Let = Let

    def c(self, v: float) -> str:
        return self.isa.literal_vec(self.st, v, Type(self.s))

    def let(self, stem: str, expr: str) -> str:
        name = fresh_name(self.st.used, f"{self.out}_{stem}")
        self.lets.append(self._Let(self.T, name, expr))
        return name

    def op(self, opcode: str, *args: str) -> str:
        fmt = self.isa.OPS[(opcode, self.isa.home(self.s))]
        return fmt.format(*args, **self.isa.fields(self.st, self.s))

    def horner(self, coefs: tuple[float, ...], x: str, stem: str) -> str:
        """sum coefs[k] x^k (constant term first)."""
        p = self.c(coefs[-1])
        for k, a in enumerate(reversed(coefs[:-1])):
            p = self.let(f"{stem}{k}", self.op("madd", p, x, self.c(a)))
        return p

    def finish(self, expr: str) -> list:
        self.lets.append(self._Let(self.T, self.out, expr))
        return self.lets


def exp_steps(b: Builder, x: str, stem: str = "e") -> str:
    """exp(x) as steps of b; returns the name of the result (not yet named b.out)."""
    k = _kind(b.s)
    lo, hi, c1, c2, deg = EXP[k]
    xc = b.let(f"{stem}x", b.op("min", b.op("max", x, b.c(lo)), b.c(hi)))
    n = b.let(f"{stem}n", b.isa.vround(b.st, b.s, b.op("mul", xc, b.c(LOG2E))))
    r = b.let(f"{stem}r", b.op("nmadd", n, b.c(c2), b.op("nmadd", n, b.c(c1), xc)))
    coefs = [1.0]
    for j in range(1, deg + 1):
        coefs.append(coefs[-1] / j)
    p = b.horner(tuple(coefs), r, f"{stem}p")
    n1 = b.let(f"{stem}n1", b.isa.vround(b.st, b.s, b.op("mul", n, b.c(0.5))))
    n2 = b.op("sub", n, n1)
    return b.let(stem, b.op("mul", b.op("mul", p, b.isa.vpow2(b.st, b.s, n1)), b.isa.vpow2(b.st, b.s, n2)))


def exp(isa: "Simd", st: "EmitState", x: str, s: Scalar, out: str) -> list:
    b = Builder(isa, st, s, out)
    return b.finish(exp_steps(b, x))


def erfc(isa: "Simd", st: "EmitState", x: str, s: Scalar, out: str) -> list:
    b = Builder(isa, st, s, out)
    k = _kind(s)
    K = ERFCX_K
    a = b.let("a", b.op("min", b.op("abs", x), b.c(ERFC_AMAX[k])))
    d = b.let("d", b.op("div", b.c(1.0), b.op("add", a, b.c(K))))
    t = b.let("t", b.op("nmadd", b.c(2 * K), d, b.c(1.0)))
    q = b.horner(ERFCX_Q[k], t, "q")
    h = b.let("h", b.op("mul", a, a))
    lo = b.let("l", b.op("msub", a, a, h))
    e = exp_steps(b, b.op("neg", h), "e")
    e2 = b.let("ec", b.op("nmadd", e, lo, e))
    r = b.let("r", b.op("mul", e2, b.op("mul", q, b.op("mul", d, b.c(K)))))
    return b.finish(b.isa.select_negative(st, s, x, b.op("sub", b.c(2.0), r), r))


FUNCTIONS = {"exp": exp, "erfc": erfc}
