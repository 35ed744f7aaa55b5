"""The opcode table of the IR: name -> (number of arguments, category).

Semantics (every backend must implement exactly these; the reference backend is
the executable definition):

  const                     a literal (attr Const); a vector-typed const is a splat
  param                     a kernel parameter (attr ParamRef)
  load                      a member of EPI/EPJ/FORCE (attr MemberRef); FORCE: value on entry
  table  (idx)              coefficient idx of table attr.name
  neg not                   -a, !a
  add sub mul div           elementwise; mul/div accept a scalar with a vector (broadcast)
  eq ne lt gt le ge         comparisons -> BOOL
  and or                    on BOOL
  select (m, a, b)          m ? a : b   (m is a scalar BOOL, a and b may be vectors)
  sqrt rsqrt inv exp erfc log floor abs  rsqrt(x) = 1/sqrt(x), inv(x) = 1/x, erfc = 1 - erf
  rsqrt2                    2/sqrt(x), exactly 2 * rsqrt(x) (made by the defer_scale pass:
                            a Newton step of 1/sqrt has a factor 1/2 this form leaves out)
  min max pow
  madd msub nmadd nmsub (a, b, c)        a*b+c, a*b-c, -(a*b)+c, -(a*b)-c
  cast                      conversion to op.type
  dot cross comp insert     vector ops, removed by the expand_vectors pass:
                            comp (attr Comp) extracts a component,
                            insert (v, s) (attr Comp) replaces one
  accum (v [, m])           FORCE.member (attr Reduce) op= v, only where mask m holds;
                            kind add/sub accumulate sums, mul/div products, max/min extrema;
                            add/sub carry attr.scale (a power of two, default 1): the sum
                            of the v is multiplied by it once, when it is added to FORCE
"""
from __future__ import annotations

ARITY: dict[str, int | tuple[int, int]] = {
    "const": 0, "param": 0, "load": 0, "table": 1,
    "neg": 1, "not": 1,
    "add": 2, "sub": 2, "mul": 2, "div": 2,
    "eq": 2, "ne": 2, "lt": 2, "gt": 2, "le": 2, "ge": 2,
    "and": 2, "or": 2, "select": 3,
    "sqrt": 1, "rsqrt": 1, "rsqrt2": 1, "inv": 1, "exp": 1, "erfc": 1, "log": 1, "floor": 1, "abs": 1,
    "min": 2, "max": 2, "pow": 2,
    "madd": 3, "msub": 3, "nmadd": 3, "nmsub": 3,
    "cast": 1, "dot": 2, "cross": 2, "comp": 1, "insert": 2,
    "accum": (1, 2),
}
COMPARISONS = frozenset({"eq", "ne", "lt", "gt", "le", "ge"})
LOGICAL = frozenset({"and", "or", "not"})
ELEMENTWISE = frozenset(
    {"neg", "add", "sub", "mul", "div", "sqrt", "rsqrt", "rsqrt2", "inv", "exp", "erfc", "log", "floor", "abs",
     "min", "max", "pow", "madd", "msub", "nmadd", "nmsub", "cast"}
)
VECTOR_ONLY = frozenset({"dot", "cross", "comp", "insert"})
FMA = frozenset({"madd", "msub", "nmadd", "nmsub"})
# Operations without side effects whose result may be removed when unused.
PURE = frozenset(ARITY) - {"accum"}
REDUCE_KINDS = ("add", "sub", "mul", "div", "max", "min")
