"""Native code for a model's CasADi Functions, compiled once and cached on disk.

CasADi evaluates an SX Function on its virtual machine, one instruction at a
time. :func:`compile_function` writes the Function out as C
(``casadi.CodeGenerator``), compiles it with the system C compiler into a
shared library and loads it back with ``casadi.external``: same name, inputs
and outputs, about six times faster for the 6R observation matrix.

Libraries are kept in a cache directory (``$DOE_CALIB_CACHE``, default
``~/.cache/doe_calib``) under a SHA-256 of the generated source, the
compiler and its flags, so building the same model again loads in
milliseconds. Each library is written to a temporary file and renamed into
place, so concurrent processes never load a half-written file.

When there is no C compiler, or it fails, a :class:`CompilationWarning` says
so and the Function is returned unchanged (slower, same results).
"""
from __future__ import annotations

import hashlib
import logging
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from functools import lru_cache
from pathlib import Path

import casadi as ca

from doe_calib.errors import CompilationWarning

log = logging.getLogger(__name__)

#: Compiler flags. -O1 runs within a few per cent of -O2/-O3 on these
#: straight-line functions and compiles twice as fast; -ffast-math is never
#: used (it would change the results).
FLAGS = ("-O1", "-fPIC", "-shared")
_SUFFIX = {"darwin": ".dylib", "win32": ".dll"}.get(sys.platform, ".so")


def cache_dir() -> Path:
    """Directory of the compiled libraries: ``$DOE_CALIB_CACHE`` or ``~/.cache/doe_calib``."""
    env = os.environ.get("DOE_CALIB_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "doe_calib"


def find_compiler() -> str | None:
    """Path of the C compiler: ``$CC``, else ``cc``, ``gcc`` or ``clang``; None if none."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        path = shutil.which(name) if name else None
        if path:
            return path
    return None


@lru_cache(maxsize=8)
def _compiler_identity(compiler: str) -> str:
    try:
        out = subprocess.run([compiler, "--version"], capture_output=True, text=True, timeout=30)
        return compiler + "\n" + out.stdout
    except (OSError, subprocess.SubprocessError):
        return compiler


def _source(function: ca.Function) -> str:
    gen = ca.CodeGenerator(f"{function.name()}.c", {"with_header": False})
    gen.add(function)
    return gen.dump()


def library_path(name: str, source: str, flags=FLAGS, compiler=None) -> Path | None:
    """Where :func:`compile_functions` keeps the library of ``source`` made by ``compiler``
    (default :func:`find_compiler`; None: no compiler)."""
    compiler = compiler or find_compiler()
    if compiler is None:
        return None
    key = hashlib.sha256("\0".join([source, _compiler_identity(compiler), *flags,
                                    sys.platform]).encode()).hexdigest()
    return cache_dir() / f"{name}-{key[:24]}{_SUFFIX}"


def load_function(function: ca.Function, path: Path) -> ca.Function:
    """The Function named as ``function`` in the library at ``path``, checked against its
    signature (names, inputs, outputs and their sparsity).

    Raises
    ------
    RuntimeError
        The library cannot be loaded or holds no such Function.
    """
    def signature(f):
        return (f.name_in(), f.name_out(), [f.sparsity_in(i) for i in range(f.n_in())],
                [f.sparsity_out(i) for i in range(f.n_out())])

    loaded = ca.external(function.name(), str(path))
    if signature(loaded) != signature(function):
        raise RuntimeError(f"{path} does not hold a function matching {function}")
    return loaded


def compile_function(function: ca.Function, flags=FLAGS) -> ca.Function:
    """The Function compiled to native code (or unchanged, with a warning, if that fails).

    Parameters
    ----------
    function : casadi.Function
        Any Function CasADi can generate C code for (SX or MX).
    flags : sequence of str
        C compiler flags; must produce a shared library.

    Returns
    -------
    casadi.Function
        An external Function with the same name, inputs and outputs, loaded
        from the cache directory (see :func:`cache_dir`); ``function``
        itself when no compiler is found or compilation fails.

    Examples
    --------
    >>> import casadi as ca
    >>> x = ca.SX.sym("x", 2)
    >>> f = ca.Function("norm2", [x], [ca.dot(x, x)], ["x"], ["y"])
    >>> g = compile_function(f)
    >>> float(g([3.0, 4.0]))
    25.0
    """
    return compile_functions([function], flags)[0]


def compile_functions(functions, flags=FLAGS, sources=None) -> list:
    """:func:`compile_function` for several Functions, compiled in parallel.

    Parameters
    ----------
    functions : sequence of casadi.Function
    flags : sequence of str
        C compiler flags for CasADi's own code.
    sources : sequence of (str, sequence of str) or None, optional
        For each Function, None (CasADi's code generator writes its C) or
        C source and its compiler flags written elsewhere, with the Function's
        name, inputs and outputs (:func:`doe_calib.model.simd_code.simd_source`).

    Returns the list of compiled Functions in the order given; any that
    cannot be compiled is returned unchanged, with a :class:`CompilationWarning`.
    """
    functions = list(functions)
    sources = [None] * len(functions) if sources is None else list(sources)
    out = list(functions)
    compiler = find_compiler()
    if compiler is None:
        warnings.warn("no C compiler (cc, gcc or clang; or $CC) was found, so the model's "
                      "functions run on CasADi's virtual machine: same results, several times "
                      "slower", CompilationWarning, stacklevel=3)
        return out
    pending = []
    for i, (f, given) in enumerate(zip(functions, sources)):
        source, own_flags = given if given is not None else (None, tuple(flags))
        try:
            source = _source(f) if source is None else source
        except RuntimeError as err:
            _fail(f, f"CasADi cannot generate C code for it ({_first_line(err)})")
            continue
        path = library_path(f.name(), source, own_flags, compiler)
        if path.exists():
            try:
                out[i] = load_function(f, path)
                log.debug("loaded %s from %s", f.name(), path)
                continue
            except RuntimeError:
                log.info("cached library %s could not be loaded; compiling it again", path)
        pending.append((i, f, source, path, own_flags))
    start = time.perf_counter()
    for i, f, path, error in _build_all(pending, compiler):
        if error is not None:
            _fail(f, error)
            continue
        try:
            out[i] = load_function(f, path)
        except RuntimeError as err:
            _fail(f, f"the compiled library could not be loaded ({_first_line(err)})")
    if pending:
        log.info("compiled %d function(s) in %.1f s (%s)", len(pending),
                 time.perf_counter() - start, ", ".join(job[1].name() for job in pending))
    return out


def _build_all(pending, compiler):
    """Compile every pending source, one process per CPU at most; list of (i, f, path, error)."""
    if not pending:
        return []
    results = []
    jobs = max(1, os.cpu_count() or 1)
    try:
        cache_dir().mkdir(parents=True, exist_ok=True)
        work = tempfile.TemporaryDirectory(prefix="build-", dir=cache_dir())
    except OSError as err:
        return [(i, f, path, f"the cache directory {cache_dir()} is not writable ({err})")
                for i, f, _, path, _ in pending]
    with work as tmp:
        running = []
        try:
            for k, (i, f, source, path, flags) in enumerate(pending):
                running.append(_start(i, f, source, path, compiler, flags, Path(tmp)))
                while running and (len(running) >= jobs or k == len(pending) - 1):
                    results.append(_finish(*running.pop(0)))
        finally:  # interrupted: stop the compilers still running
            for job in running:
                if not isinstance(job[4], OSError):
                    job[4].kill()
                    job[4].wait()
    return results


def _start(i, f, source, path, compiler, flags, tmp):
    src = tmp / f"{path.stem}.c"
    src.write_text(source)
    lib = tmp / f"{path.stem}{_SUFFIX}"
    cmd = [compiler, *flags, str(src), "-o", str(lib)]
    if sys.platform.startswith("linux"):
        cmd.append("-lm")
    try:
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    except OSError as err:
        proc = err
    return i, f, path, lib, proc, time.perf_counter()


def _finish(i, f, path, lib, proc, start):
    if isinstance(proc, OSError):
        return i, f, path, f"the C compiler could not be run ({proc})"
    output, _ = proc.communicate()
    if proc.returncode != 0:
        tail = "\n".join(output.strip().splitlines()[-5:])
        return i, f, path, f"the C compiler failed (exit {proc.returncode}): {tail}"
    try:
        os.replace(lib, path)  # atomic: a concurrent reader sees the old file or the new one
    except OSError as err:
        return i, f, path, f"the library could not be stored in {path.parent} ({err})"
    log.info("compiled %s (%d instructions) in %.1f s into %s", f.name(), _instructions(f),
             time.perf_counter() - start, path)
    return i, f, path, None


def _instructions(f) -> int:
    try:
        return int(f.n_instructions())
    except RuntimeError:
        return -1


def _fail(function, why: str) -> None:
    warnings.warn(f"{function.name()} was not compiled to native code, because {why}; it runs "
                  f"on CasADi's virtual machine instead: same results, several times slower",
                  CompilationWarning, stacklevel=4)


def _first_line(err) -> str:
    lines = [s for s in str(err).splitlines() if s.strip()]
    return lines[-1].strip() if lines else type(err).__name__
