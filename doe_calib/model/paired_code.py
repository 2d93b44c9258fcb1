"""C code that evaluates an SX Function for two configurations at once, one per SIMD lane.

CasADi's code generator writes one scalar C statement per instruction of the
Function's algorithm. :func:`paired_source` writes the same algorithm on
pairs of doubles (GCC/Clang vector extensions: ``double`` × 2, SSE2 on any
x86-64, NEON on 64-bit ARM): each instruction computes two configurations in
one machine operation, so a batch of M poses runs M / 2 times through the
instruction list instead of M times (the 6R observation matrix: 19 534
instructions per call).

Every lane does the scalar instruction's IEEE arithmetic (``+ − × ÷``
element-wise; ``sin``, ``cos``, ``sqrt`` … called on each lane by the same C
library CasADi's own code calls), so both lanes give the numbers CasADi's
code gives, to the bit; ``-ffp-contract=off`` (:data:`FLAGS`) keeps the
compiler from fusing a multiply and an add where CasADi's code would not.

The source holds two entry points, loaded with ``casadi.external``:

``<name>``
    One configuration; the Function's own name, inputs and outputs.
``<name>_pair``
    Two configurations: every input not in ``shared`` and every output
    twice as wide (side by side), the signature of
    ``function.map(2)`` with ``shared`` inputs not repeated (:func:`pair_signature`).
"""
from __future__ import annotations

import casadi as ca

from doe_calib.model import compiled

#: Compiler flags for paired code: those of :data:`doe_calib.model.compiled.FLAGS`,
#: and no fused multiply-add (which would round differently from CasADi's code).
FLAGS = (*compiled.FLAGS, "-ffp-contract=off")

#: Statements per C function (see ``_body``).
PART = 1000
#: Most work pairs kept on the stack (16 bytes each); a larger Function keeps CasADi's code.
MAX_WORK = 32768

_BINARY = {ca.OP_ADD: "+", ca.OP_SUB: "-", ca.OP_MUL: "*", ca.OP_DIV: "/"}
#: Scalar C for the instructions computed lane by lane, as CasADi's code generator writes it.
_LANEWISE = {
    **{getattr(ca, f"OP_{f.upper()}"): f + "({x})" for f in (
        "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh",
        "atanh", "exp", "log", "expm1", "log1p", "sqrt", "fabs", "floor", "ceil", "erf")},
    **{getattr(ca, f"OP_{f.upper()}"): f + "({x}, {y})" for f in (
        "atan2", "pow", "fmin", "fmax", "fmod", "hypot", "copysign")},
    ca.OP_CONSTPOW: "pow({x}, {y})", ca.OP_SIGN: "({x}<0 ? -1 : {x}>0 ? 1 : {x})",
    ca.OP_NOT: "(!{x})", ca.OP_LT: "({x}<{y})", ca.OP_LE: "({x}<={y})", ca.OP_EQ: "({x}=={y})",
    ca.OP_NE: "({x}!={y})", ca.OP_AND: "({x}&&{y})", ca.OP_OR: "({x}||{y})",
    ca.OP_IF_ELSE_ZERO: "({x} ? {y} : 0)",
}

_PREAMBLE = """\
/* {name}: two configurations per instruction (doe_calib.model.paired_code) */
#include <math.h>
typedef long long int casadi_int;
typedef double v2 __attribute__((vector_size(16)));
#if defined(_WIN32) || defined(__CYGWIN__)
#define EXPORT __declspec(dllexport)
#else
#define EXPORT
#endif
#if defined(__GNUC__)
#define NOINLINE __attribute__((noinline))
#else
#define NOINLINE
#endif
static const double zeros[{zeros}];
"""

_ENTRY = """\
EXPORT int {entry}(const double** arg, double** res, casadi_int* iw, double* w, int mem) {{
  const double *a0[{n_in}], *a1[{n_in}];
  double *r0[{n_out}], *r1[{n_out}];
  v2 W[{n_w}];
{setup}{calls}
  return 0;
}}
EXPORT int {entry}_checkout(void) {{ return 0; }}
EXPORT void {entry}_release(int mem) {{ }}
EXPORT void {entry}_incref(void) {{ }}
EXPORT void {entry}_decref(void) {{ }}
EXPORT casadi_int {entry}_n_in(void) {{ return {n_in}; }}
EXPORT casadi_int {entry}_n_out(void) {{ return {n_out}; }}
EXPORT double {entry}_default_in(casadi_int i) {{ return 0; }}
EXPORT const char* {entry}_name_in(casadi_int i) {{
  switch (i) {{ {names_in} default: return 0; }}
}}
EXPORT const char* {entry}_name_out(casadi_int i) {{
  switch (i) {{ {names_out} default: return 0; }}
}}
EXPORT const casadi_int* {entry}_sparsity_in(casadi_int i) {{
  switch (i) {{ {sparsity_in} default: return 0; }}
}}
EXPORT const casadi_int* {entry}_sparsity_out(casadi_int i) {{
  switch (i) {{ {sparsity_out} default: return 0; }}
}}
EXPORT int {entry}_work(casadi_int* sz_arg, casadi_int* sz_res, casadi_int* sz_iw,
                        casadi_int* sz_w) {{
  *sz_arg = {n_in}; *sz_res = {n_out}; *sz_iw = 0; *sz_w = {sz_w};
  return 0;
}}
"""


def pair_signature(function: ca.Function, shared=(3,)) -> ca.Function:
    """``function`` mapped over two configurations, ``shared`` inputs not repeated.

    The reference the ``<name>_pair`` entry point is checked against when loaded,
    and what it computes.
    """
    return function.map(f"{function.name()}_pair", "serial", 2, list(shared), [])


def load_pair(function: ca.Function, source: str, shared=(3,)) -> ca.Function | None:
    """The ``<name>_pair`` Function of ``source`` once :func:`~doe_calib.model.compiled.\
compile_functions` has compiled it (with :data:`FLAGS`); None when its library is not there.
    """
    path = compiled.library_path(function.name(), source, FLAGS)
    if path is None or not path.exists():
        return None
    try:
        return compiled.load_function(pair_signature(function, shared), path)
    except RuntimeError:
        return None


def paired_source(function: ca.Function, shared=(3,)) -> str | None:
    """C source of ``function`` on two SIMD lanes, or None when it cannot be written.

    Parameters
    ----------
    function : casadi.Function
        An SX Function with dense inputs and outputs (a model's ``observation``).
    shared : tuple of int
        Inputs the two configurations share (the parameters ``p``: input 3).

    Returns
    -------
    str or None
        Source with the entry points ``<name>`` and ``<name>_pair`` (module
        docstring); None for an MX Function, sparse inputs or outputs, or an
        instruction this module does not write (CasADi's own code then serves).

    Notes
    -----
    The instructions are those of ``function`` after common-subexpression
    elimination (``casadi.cse``): an expression written twice in the graph is
    computed once, with the same operands, so to the same bits. CasADi's
    reverse mode writes ``cos θ`` anew for each sweep through ``sin θ``: the
    6R observation has 99 sines and 99 cosines, 34 of each after it (0.1 s, at
    compile time only).
    """
    if not function.is_a("SXFunction") or not all(
            function.sparsity_in(i).is_dense() for i in range(function.n_in())) or not all(
            function.sparsity_out(i).is_dense() for i in range(function.n_out())):
        return None
    ins = function.sx_in()
    function = ca.Function(function.name(), ins, ca.cse(function.call(ins)),
                           function.name_in(), function.name_out())
    n_w = max(function.sz_w(), 1)
    body = _body(function) if n_w <= MAX_WORK else None
    if body is None:
        return None
    calls = "".join(f"  part{c}(a0, a1, r0, r1, W);\n"
                    for c in range(-(-function.n_instructions() // PART)))
    name = function.name()
    n_in, n_out = function.n_in(), function.n_out()
    nnz_in = [function.nnz_in(i) for i in range(n_in)]
    nnz_out = [function.nnz_out(i) for i in range(n_out)]
    offsets = [sum(nnz_out[:i]) for i in range(n_out)]
    total = sum(nnz_out)
    parts = [_PREAMBLE.format(name=name, zeros=max(nnz_in + [1])), *body]
    for entry, pair in ((name, False), (f"{name}_pair", True)):
        setup = []
        for i in range(n_in):
            setup.append(f"  a0[{i}] = arg[{i}] ? arg[{i}] : zeros;\n")
            lane = f"arg[{i}] ? arg[{i}] + {nnz_in[i]} : zeros" if pair and i not in shared \
                else f"a0[{i}]"
            setup.append(f"  a1[{i}] = {lane};\n")
        for i in range(n_out):
            if pair:
                setup.append(f"  r0[{i}] = res[{i}] ? res[{i}] : w + {2 * offsets[i]};\n"
                             f"  r1[{i}] = r0[{i}] + {nnz_out[i]};\n")
            else:
                setup.append(f"  r1[{i}] = w + {offsets[i]};\n"
                             f"  r0[{i}] = res[{i}] ? res[{i}] : r1[{i}];\n")
        sparsity = []
        for kind, count, size in (("in", n_in, function.size_in), ("out", n_out,
                                                                    function.size_out)):
            for i in range(count):
                rows, cols = size(i)
                wide = 2 if pair and not (kind == "in" and i in shared) else 1
                parts.append(f"static const casadi_int s_{entry}_{kind}{i}[3] = "
                             f"{{{rows}, {cols * wide}, 1}};")
                sparsity.append((kind, f"case {i}: return s_{entry}_{kind}{i};"))
        parts.append(_ENTRY.format(
            entry=entry, n_in=n_in, n_out=n_out, setup="".join(setup), n_w=n_w, calls=calls,
            sz_w=2 * total,
            names_in=" ".join(f'case {i}: return "{function.name_in(i)}";' for i in range(n_in)),
            names_out=" ".join(f'case {i}: return "{function.name_out(i)}";'
                               for i in range(n_out)),
            sparsity_in=" ".join(s for k, s in sparsity if k == "in"),
            sparsity_out=" ".join(s for k, s in sparsity if k == "out")))
    return "\n".join(parts) + "\n"


def _constant(value: float) -> str:
    c = value.hex() if value == value and abs(value) != float("inf") else \
        ("NAN" if value != value else ("INFINITY" if value > 0 else "-INFINITY"))
    return f"(v2){{{c}, {c}}}"


def _body(function: ca.Function) -> list | None:
    """The instructions as C functions of :data:`PART` statements each on the pairs ``W[i]``.

    Parts, not one function: GCC's register allocation grows faster than the
    length of a function (one 19 534-statement function on pairs compiles
    three times slower than CasADi's scalar code; parts of 1000 faster than it),
    and the work pairs in memory cost little (stores go alongside the arithmetic).
    None if an instruction is not one this module writes.
    """
    statements = []
    for k in range(function.n_instructions()):
        line = _statement(function, k)
        if line is None:
            return None
        statements.append(line)
    parts = []
    for c in range(0, len(statements), PART):
        parts += [f"static void NOINLINE part{c // PART}(const double** A0, const double** A1, "
                  "double** R0, double** R1, v2* restrict W) {", *statements[c:c + PART], "}"]
    return parts


def _statement(function: ca.Function, k: int) -> str | None:
    op = function.instruction_id(k)
    out, ins = function.instruction_output(k), function.instruction_input(k)
    if op == ca.OP_INPUT:
        return f"  W[{out[0]}] = (v2){{A0[{ins[0]}][{ins[1]}], A1[{ins[0]}][{ins[1]}]}};"
    if op == ca.OP_OUTPUT:
        i, nz = out
        return f"  R0[{i}][{nz}] = W[{ins[0]}][0]; R1[{i}][{nz}] = W[{ins[0]}][1];"
    if op == ca.OP_CONST:
        return f"  W[{out[0]}] = {_constant(float(function.instruction_constant(k)))};"
    x = f"W[{ins[0]}]" if ins else ""
    if op in _BINARY:
        expr = f"{x} {_BINARY[op]} W[{ins[1]}]"
    elif op == ca.OP_NEG:
        expr = f"-{x}"
    elif op == ca.OP_SQ:
        expr = f"{x} * {x}"
    elif op == ca.OP_TWICE:
        expr = f"{x} + {x}"
    elif op == ca.OP_INV:
        expr = f"(v2){{1., 1.}} / {x}"
    elif op in _LANEWISE:
        lanes = [_LANEWISE[op].format(x=f"{x}[{lane}]",
                                      y=f"W[{ins[1]}][{lane}]" if len(ins) > 1 else "")
                 for lane in (0, 1)]
        expr = f"(v2){{{lanes[0]}, {lanes[1]}}}"
    else:
        return None
    return f"  W[{out[0]}] = {expr};"
