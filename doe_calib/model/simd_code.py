"""C code that evaluates an SX Function for several configurations at once, one per SIMD lane.

CasADi's code generator writes one scalar C statement per instruction of the
Function's algorithm. :func:`simd_source` writes the same algorithm on
vectors of doubles (GCC/Clang vector extensions): each instruction computes
two configurations in one machine operation (SSE2, any x86-64; NEON, 64-bit
ARM), or four where the CPU has AVX (:func:`simd_lanes`), so a batch of M
poses runs M / 2 or M / 4 times through the instruction list instead of M
times. For the 6R observation matrix (19 534 instructions, about 250 kB of
machine code, more than the CPU's instruction cache) the code itself is the
cost: a pass over it costs about the same with one, two or four lanes.

Every lane does the scalar instruction's IEEE arithmetic (``+ − × ÷``
element-wise; ``sin``, ``cos``, ``sqrt`` … called on each lane by the same C
library CasADi's own code calls), so every lane gives the numbers CasADi's
code gives, to the bit; ``-ffp-contract=off`` keeps the compiler from fusing
a multiply and an add where CasADi's code would not.

The source holds two entry points, loaded with ``casadi.external``:

``<name>``
    One configuration; the Function's own name, inputs and outputs.
``<name>_lanes``
    L configurations (L = the lanes): every input but the parameters (:data:`SHARED`) and
    every output L times as wide (side by side), the signature of
    ``function.map(L)`` with the parameters not repeated (:func:`lanes_signature`).
"""
from __future__ import annotations

import platform
from functools import lru_cache
from pathlib import Path

import casadi as ca

from doe_calib.model import compiled

#: Statements per C function (see ``_body``).
PART = 1000
#: The inputs every configuration shares: the parameters ``p``.
SHARED = (3,)
#: Most bytes of work vectors on the stack (a thread's stack may be 512 kB); a Function
#: needing more keeps CasADi's code.
MAX_WORK_BYTES = 128 * 1024

#: C for the instructions computed on whole vectors (``one``: a vector of ones).
_VECTOR = {ca.OP_ADD: "{x} + {y}", ca.OP_SUB: "{x} - {y}", ca.OP_MUL: "{x} * {y}",
           ca.OP_DIV: "{x} / {y}", ca.OP_NEG: "-{x}", ca.OP_SQ: "{x} * {x}",
           ca.OP_TWICE: "{x} + {x}", ca.OP_INV: "{one} / {x}"}
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
/* {name}: {lanes} configurations per instruction (doe_calib.model.simd_code) */
#include <math.h>
typedef long long int casadi_int;
typedef double vec __attribute__((vector_size({bytes})));
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
/* AVX code leaves the upper halves of the vector registers dirty, and SSE code run
   after it (the C library's, Pinocchio's, numpy's) then runs 2-3 times slower:
   clean them before calling out and before returning (GCC does so only from -O2). */
#if defined(__AVX__) && defined(__GNUC__)
#define CLEAN_UPPER() __builtin_ia32_vzeroupper()
#else
#define CLEAN_UPPER()
#endif
static const double zeros[{zeros}];
"""

#: An entry point; it refuses to run AVX code on a CPU without it (a cache shared between
#: machines).
_ENTRY = """\
EXPORT int {entry}(const double** arg, double** res, casadi_int* iw, double* w, int mem) {{
  const double *a[{n_a}];
  double *r[{n_r}];
  vec W[{n_w}];
#if defined(__AVX__) && defined(__GNUC__)
  if (!__builtin_cpu_supports("avx")) return 1;
#endif
{setup}{calls}
  CLEAN_UPPER();
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


@lru_cache(maxsize=1)
def simd_lanes() -> int:
    """Configurations per instruction on this machine: 4 on an x86-64 CPU with AVX
    (Linux, read from ``/proc/cpuinfo``), else 2."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return 2
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return 2
    flags = next((line.split(":", 1)[1].split() for line in text.splitlines()
                  if line.startswith("flags")), [])
    return 4 if "avx" in flags else 2


def flags(lanes: int) -> tuple:
    """Compiler flags of SIMD code: :data:`doe_calib.model.compiled.FLAGS`, no fused
    multiply-add (it would round differently from CasADi's code), ``-mavx`` for 4 lanes."""
    return (*compiled.FLAGS, "-ffp-contract=off", *(("-mavx",) if lanes == 4 else ()))


def lanes_signature(function: ca.Function, lanes: int) -> ca.Function:
    """``function`` mapped over ``lanes`` configurations, :data:`SHARED` inputs not repeated.

    The reference the ``<name>_lanes`` entry point is checked against when
    loaded, and what it computes.
    """
    return function.map(f"{function.name()}_lanes", "serial", lanes, list(SHARED), [])


def load_lanes(function: ca.Function, source: str, lanes: int) -> ca.Function | None:
    """The ``<name>_lanes`` Function of ``source`` once :func:`~doe_calib.model.compiled.\
compile_functions` has compiled it (with :func:`flags`); None when its library is not there.
    """
    path = compiled.library_path(function.name(), source, flags(lanes))
    if path is None or not path.exists():
        return None
    try:
        return compiled.load_function(lanes_signature(function, lanes), path)
    except RuntimeError:
        return None


def simd_source(function: ca.Function, lanes: int = 2) -> str | None:
    """C source of ``function`` on ``lanes`` SIMD lanes, or None when it cannot be written.

    Parameters
    ----------
    function : casadi.Function
        An SX Function with dense inputs and outputs (a model's ``observation``).
    lanes : int
        2, or 4 (AVX, compiled with ``-mavx``: :func:`simd_lanes`, :func:`flags`).

    Returns
    -------
    str or None
        Source with the entry points ``<name>`` and ``<name>_lanes`` (module
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
    if lanes not in (2, 4):
        raise ValueError(f"lanes must be 2 or 4, not {lanes}")
    if not function.is_a("SXFunction") or not all(
            function.sparsity_in(i).is_dense() for i in range(function.n_in())) or not all(
            function.sparsity_out(i).is_dense() for i in range(function.n_out())):
        return None
    ins = function.sx_in()
    function = ca.Function(function.name(), ins, ca.cse(function.call(ins)),
                           function.name_in(), function.name_out())
    n_w = max(function.sz_w(), 1)
    body = _body(function, lanes) if n_w * 8 * lanes <= MAX_WORK_BYTES else None
    if body is None:
        return None
    n_in, n_out = function.n_in(), function.n_out()
    calls = "".join(f"  part{c}(a, r, W);\n"
                    for c in range(-(-function.n_instructions() // PART)))
    name = function.name()
    nnz_in = [function.nnz_in(i) for i in range(n_in)]
    nnz_out = [function.nnz_out(i) for i in range(n_out)]
    offsets = [sum(nnz_out[:i]) for i in range(n_out)]
    total = sum(nnz_out)
    parts = [_PREAMBLE.format(name=name, lanes=lanes, bytes=8 * lanes,
                              zeros=max(nnz_in + [1])), *body]
    for entry, wide in ((name, False), (f"{name}_lanes", True)):
        setup = []
        for lane in range(lanes):
            for i in range(n_in):
                step = nnz_in[i] * lane if wide and i not in SHARED else 0
                setup.append(f"  a[{lane * n_in + i}] = arg[{i}] ? arg[{i}] + {step} : zeros;\n")
            for i in range(n_out):
                scratch = f"w + {lanes * offsets[i] + lane * nnz_out[i]}"
                mine = f"res[{i}] + {nnz_out[i] * lane}" if wide else \
                    (f"res[{i}]" if lane == 0 else None)
                setup.append(f"  r[{lane * n_out + i}] = " + (
                    f"res[{i}] ? {mine} : {scratch};\n" if mine else f"{scratch};\n"))
        sparsity = []
        for kind, count, size in (("in", n_in, function.size_in),
                                  ("out", n_out, function.size_out)):
            for i in range(count):
                rows, cols = size(i)
                times = lanes if wide and not (kind == "in" and i in SHARED) else 1
                parts.append(f"static const casadi_int s_{entry}_{kind}{i}[3] = "
                             f"{{{rows}, {cols * times}, 1}};")
                sparsity.append((kind, f"case {i}: return s_{entry}_{kind}{i};"))
        parts.append(_ENTRY.format(
            entry=entry, n_in=n_in, n_out=n_out, n_a=lanes * max(n_in, 1), sz_w=lanes * total,
            n_r=lanes * max(n_out, 1), setup="".join(setup), n_w=n_w, calls=calls,
            names_in=" ".join(f'case {i}: return "{function.name_in(i)}";' for i in range(n_in)),
            names_out=" ".join(f'case {i}: return "{function.name_out(i)}";'
                               for i in range(n_out)),
            sparsity_in=" ".join(s for k, s in sparsity if k == "in"),
            sparsity_out=" ".join(s for k, s in sparsity if k == "out")))
    return "\n".join(parts) + "\n"


def _constant(value: float, lanes: int) -> str:
    c = value.hex() if value == value and abs(value) != float("inf") else \
        ("NAN" if value != value else ("INFINITY" if value > 0 else "-INFINITY"))
    return "(vec){" + ", ".join([c] * lanes) + "}"


def _body(function: ca.Function, lanes: int) -> list | None:
    """The instructions as C functions of :data:`PART` statements each on the vectors ``W[i]``.

    Parts, not one function: GCC's register allocation grows faster than the
    length of a function (one 19 534-statement function on pairs compiles
    three times slower than CasADi's scalar code; parts of 1000 faster than it).
    The work vectors stay in memory: local variables per part (loaded and
    stored where parts meet) give the same bits but larger, slower code.
    None if an instruction is not one this module writes.
    """
    n_in, n_out = function.n_in(), function.n_out()
    statements = []
    for k in range(function.n_instructions()):
        line = _statement(function, k, lanes, n_in, n_out)
        if line is None:
            return None
        statements.append(line)
    parts = []
    for c in range(0, len(statements), PART):
        parts += [f"static void NOINLINE part{c // PART}(const double** A, double** R, "
                  "vec* restrict W) {", *statements[c:c + PART], "}"]
    return parts


def _statement(function: ca.Function, k: int, lanes: int, n_in: int, n_out: int) -> str | None:
    op = function.instruction_id(k)
    out, ins = function.instruction_output(k), function.instruction_input(k)
    if op == ca.OP_INPUT:
        i, nz = ins
        return f"  W[{out[0]}] = (vec){{" + ", ".join(
            f"A[{lane * n_in + i}][{nz}]" for lane in range(lanes)) + "};"
    if op == ca.OP_OUTPUT:
        i, nz = out
        return "  " + " ".join(f"R[{lane * n_out + i}][{nz}] = W[{ins[0]}][{lane}];"
                               for lane in range(lanes))
    if op == ca.OP_CONST:
        return f"  W[{out[0]}] = {_constant(float(function.instruction_constant(k)), lanes)};"
    x = f"W[{ins[0]}]" if ins else ""
    y = f"W[{ins[1]}]" if len(ins) > 1 else ""
    if op in _VECTOR:
        expr = _VECTOR[op].format(x=x, y=y, one=_constant(1.0, lanes))
    elif op in _LANEWISE:
        expr = "(vec){" + ", ".join(_LANEWISE[op].format(x=f"{x}[{lane}]", y=f"{y}[{lane}]")
                                    for lane in range(lanes)) + "}"
    else:
        return None
    clean = "CLEAN_UPPER(); " if op in _LANEWISE else ""
    return f"  {clean}W[{out[0]}] = {expr};"
