"""User-defined effects: a Python file declaring one effect, loaded with ``--effect-file``.

:func:`load_effect_file` makes the file's effect class and changes
nothing else; a registry that holds them
(:meth:`~doe_calib.model.effects.registry.EffectRegistry.with_file`, or
:func:`~doe_calib.model.effects.registry_with_files`) lets model strings,
identification, design and diagnosis use the effect like a built-in one,
wherever that registry is passed (``registry=``).

The file declares::

    NAME = "my_effect"        # the model-string word
    PER_JOINT = True          # optional (default False): written my_effect(j3); diagnosis
                              # tries it on every joint
    PARAMETERS = [("a", "rad", 1e-4, "description"), ...]
        # (suffix, SI unit, scale, description); the unit is a key of
        # doe_calib.model.parameters.DISPLAY_UNITS ("m", "rad", "rad/(N·m)", "m/N", "1", "1/K"),
        # the scale the parameter's typical size (SI). Every parameter is nominally 0;
        # its full name is f"{NAME}_{joint}_{suffix}" (URDF joint name) when per joint,
        # f"{NAME}_{suffix}" otherwise, and its block is NAME. An optional fifth item, a
        # dict with "bounds", "plausible" and "sign", and the optional PHRASE and
        # IMPLAUSIBLE say what is known of the effect (docs/formats.md §9).

and at least one of the functions::

    def joint_correction(q, env, p, joint=None):        -> N values (rad or m)
        # added to the commanded joint positions, before any load
    def flange_correction(q, env, p, wrench, joint=None):  -> (R 3x3 or None, t 3 values)
        # rigid correction of the flange frame, expressed in the flange frame (m):
        # T_flange ← T_flange · (R, t)
    def deflection(q, env, p, tau, joint=None):          -> N values (rad or m)
        # added joint deflection from the joint torques tau (N·m or N) of the wrench

where ``q`` is the casadi SX joint vector (N, 1) (rad or m), ``env`` the SX
environment vector (1 + N: ``env[0]`` the temperature, °C, NaN when not
measured: guard it with ``casadi.if_else``; ``env[1 + k]`` the direction, +1,
−1 or 0 unknown, from which joint k reached the pose), ``p`` a dict suffix → SX of this effect's
parameters, ``wrench`` the SX 6-vector (N, N·m; flange wrench at the flange
origin, base frame), ``tau`` the SX (N, 1) joint torques and ``joint`` the
0-based joint index (None unless ``PER_JOINT``). The functions build symbolic
expressions: use casadi functions (``ca.sin``, ``ca.fabs``, ``ca.if_else``),
not ``math`` or numpy ones, and no Python ``if`` on a symbol.

A full example, a flange that droops along its z axis by ``c`` per newton of
the vertical load and shifts with the angle of one joint (m)::

    import casadi as ca

    NAME = "tool_droop"
    PER_JOINT = True
    PARAMETERS = [("c", "m/N", 1e-7, "droop of the tool per newton of vertical force"),
                  ("s", "m", 1e-4, "shift along flange x with the sine of the joint")]

    def flange_correction(q, env, p, wrench, joint=None):
        return None, [p["s"] * ca.sin(q[joint]), 0, p["c"] * wrench[2]]

A per-joint deflection example ships as ``doe_calib/examples/example_effect.py``
(:data:`doe_calib.examples.EFFECT_FILE`). Reading back a result that names the effect
needs the same file.

Examples
--------
>>> from doe_calib.examples import EFFECT_FILE
>>> from doe_calib.model.effects import DEFAULT_REGISTRY, parse_model
>>> [cls.name for cls in load_effect_file(EFFECT_FILE)]
['progressive_stiffness']
>>> mine = DEFAULT_REGISTRY.with_file(EFFECT_FILE)
>>> parse_model("progressive_stiffness(j2)", registry=mine)[0].spec()
'progressive_stiffness(j2)'
>>> "progressive_stiffness" in DEFAULT_REGISTRY   # the default registry is unchanged
False
"""
from __future__ import annotations

import importlib.util
import inspect
import math
import re
import traceback
from pathlib import Path
from types import MappingProxyType

import casadi as ca
import numpy as np

from doe_calib.errors import DataError, DoeCalibError, ModelError
from doe_calib.model.effects.base import ChainSymbols, Effect, joint_index
from doe_calib.model.parameters import DISPLAY_UNITS, Parameter

#: Function name → its arguments, in the order they are passed.
FUNCTIONS = {"joint_correction": ("q", "env", "p", "joint"),
             "flange_correction": ("q", "env", "p", "wrench", "joint"),
             "deflection": ("q", "env", "p", "tau", "joint")}

_IDENTIFIER = re.compile(r"^[A-Za-z_]\w*$")

#: Value given to every symbol to check that an expression is finite.
_GENERIC = 0.1234567


def _line(exc: BaseException, path: str):
    """The last line of ``path`` in the traceback of ``exc``, or None."""
    lines = [f.lineno for f in traceback.extract_tb(exc.__traceback__) if f.filename == path]
    return lines[-1] if lines else None


class UserEffect(Effect):
    """An effect declared in a user file; :func:`load_effect_file` makes one subclass per file."""

    name = ""
    #: A user's ``flange_correction`` may return any 3×3 matrix, not only a rotation.
    exact_rotations = False
    #: Resolved path of the declaring file.
    source = ""
    #: ((suffix, unit, scale, description, {"bounds", "plausible", "sign"}), …)
    parameter_specs = ()
    #: Function name → callable, for the functions the file defines.
    functions = MappingProxyType({})

    def __init__(self, joint=None):
        if self.per_joint and joint is None:
            raise ModelError(f"effect {self.name} (from {self.source}) sits on a joint: write "
                             f"{self.name}(j1) … or its URDF joint name")
        if not self.per_joint and joint is not None:
            raise ModelError(f"effect {self.name} (from {self.source}) is not per joint: write "
                             f"{self.name} without arguments, or set PER_JOINT = True")
        super().__init__(*(() if joint is None else (joint,)))

    @property
    def uses_torque(self) -> bool:
        return "deflection" in self.functions

    def _prefix(self, robot) -> tuple:
        if self.joint is None:
            return None, f"{self.name}_"
        k = joint_index(robot, self.joint)
        return k, f"{self.name}_{robot.joints[k].name}_"

    def parameters(self, robot) -> list:
        k, prefix = self._prefix(robot)
        where = "" if k is None else f" (joint {robot.joints[k].name})"
        return [Parameter(prefix + suffix, self.name, unit, 0.0, scale, text + where, **known)
                for suffix, unit, scale, text, known in self.parameter_specs]

    def _call(self, function: str, s: ChainSymbols, extra=None):
        k, prefix = self._prefix(s.robot)
        p = {suffix: s.p[prefix + suffix] for suffix, *_ in self.parameter_specs}
        args = (s.q, s.env, p) + (() if extra is None else (extra,)) + (k,)
        try:
            return self.functions[function](*args)
        except DoeCalibError:
            raise
        except Exception as exc:
            line = _line(exc, self.source)
            where = self.source + ("" if line is None else f", line {line}")
            raise ModelError(f"{where}: {function} of effect {self.name} raised "
                             f"{type(exc).__name__}: {exc}; build the expression from casadi "
                             f"functions (ca.sin, ca.if_else), not math or numpy, and with no "
                             f"Python 'if' on a symbol") from None

    def _checked(self, x: ca.SX, s: ChainSymbols, function: str) -> ca.SX:
        """``x`` if built from the chain's symbols only and finite at a generic point."""
        known = [s.q, s.env, *s.p.values()] + ([] if s.wrench is None else [s.wrench])
        names = {v.name() for v in ca.symvar(ca.vertcat(*known))}
        symbols = ca.symvar(x)
        foreign = sorted({v.name() for v in symbols} - names)
        if foreign:
            raise ModelError(f"{self.source}: {function} of effect {self.name} uses symbols of "
                             f"its own ({', '.join(foreign)}); build it from q, env, p, wrench "
                             f"and tau only")
        (value,) = ca.Function("check", symbols, [x]).call([_GENERIC] * len(symbols))
        if not np.all(np.isfinite(np.array(value))):
            raise ModelError(f"{self.source}: {function} of effect {self.name} is NaN or "
                             f"infinite with every input at {_GENERIC}: math and numpy functions "
                             f"of a casadi symbol give NaN; use ca.sin, ca.sqrt, ca.fabs instead")
        return x

    def _vector(self, value, n: int, s: ChainSymbols, function: str, what: str) -> ca.SX:
        try:
            if isinstance(value, np.ndarray) and value.dtype == object:
                value = list(value.ravel())
            x = ca.vertcat(*[ca.SX(v) for v in value]) if isinstance(value, (list, tuple)) \
                else ca.SX(value)
        except Exception:
            x = None
        if x is None or x.numel() != n or min(x.shape) > 1:
            shape = "an object of type " + type(value).__name__ if x is None else \
                f"shape {x.shape[0]}x{x.shape[1]}"
            raise ModelError(f"{self.source}: {function} of effect {self.name} returned {shape}; "
                             f"return {what} (a list or a casadi SX column)")
        return self._checked(ca.reshape(x, n, 1), s, function)

    def _per_joint(self, function: str, s: ChainSymbols, extra=None):
        """The file's ``function`` (joint correction or deflection): N values, or None."""
        out = self._call(function, s, extra) if function in self.functions else None
        n = s.robot.n_joints
        return None if out is None else \
            self._vector(out, n, s, function, f"{n} values, one per joint")

    def joint_correction(self, s: ChainSymbols):
        return self._per_joint("joint_correction", s)

    def deflection(self, s: ChainSymbols, tau: ca.SX):
        return self._per_joint("deflection", s, tau)

    def placement(self, s: ChainSymbols, k: int):
        if k != s.robot.n_joints or "flange_correction" not in self.functions:
            return None
        out = self._call("flange_correction", s, s.wrench)
        if out is None:
            return None
        if not isinstance(out, (list, tuple)) or len(out) != 2:
            raise ModelError(f"{self.source}: flange_correction of effect {self.name} must "
                             f"return a pair (R or None, t), got {type(out).__name__}")
        rot, t = out
        if rot is None:
            rot = ca.SX.eye(3)
        else:
            try:
                rot = ca.SX(rot) if not isinstance(rot, (list, tuple)) else \
                    ca.vertcat(*[ca.horzcat(*[ca.SX(v) for v in row]) for row in rot])
            except Exception:
                rot = None
            if rot is None or rot.shape != (3, 3):
                raise ModelError(f"{self.source}: flange_correction of effect {self.name} "
                                 f"returned a rotation that is not 3x3; return a 3x3 rotation "
                                 f"matrix or None")
            rot = self._checked(rot, s, "flange_correction")
        t = self._vector(t, 3, s, "flange_correction", "a translation of 3 values")
        return rot, [t[i] for i in range(3)]


#: What a PARAMETERS row's optional fifth item may say.
KNOWN_KEYS = ("bounds", "plausible", "sign")


def _known(extra, row, path: str, name: str) -> dict:
    """The fifth item of a PARAMETERS row: bounds and plausible range (SI), sign words."""
    fix = (f"; give a dict with keys among {', '.join(KNOWN_KEYS)}, e.g. "
           f'{{"bounds": (0, float("inf")), "sign": "positive: …"}}')
    if not isinstance(extra, dict) or set(extra) - set(KNOWN_KEYS):
        raise ModelError(f"{path}: the fifth item of parameter {row[0]!r} of effect {name} is "
                         f"{extra!r}{fix}")
    out = dict(extra)
    for key in ("bounds", "plausible"):
        if key in out:
            try:
                low, high = (float(v) for v in out[key])
            except (TypeError, ValueError):
                low = high = float("nan")
            if not low <= high:
                raise ModelError(f"{path}: {key} of parameter {row[0]!r} of effect {name} must "
                                 f"be (low, high) with low ≤ high (SI), got {out[key]!r}")
            out[key] = (low, high)
    if not isinstance(out.get("sign", ""), str):
        raise ModelError(f"{path}: sign of parameter {row[0]!r} of effect {name} must be words")
    return out


def _parameter_specs(rows, path: str, name: str) -> tuple:
    fix = (f'; declare PARAMETERS = [("a", "rad", 1e-4, "description"), …] with units from '
           f'{", ".join(DISPLAY_UNITS)}')
    if rows is None:
        raise ModelError(f"{path}: effect {name} declares no PARAMETERS{fix}")
    if not isinstance(rows, (list, tuple)) or not rows:
        raise ModelError(f"{path}: PARAMETERS of effect {name} must be a non-empty list{fix}")
    out = []
    for row in rows:
        ok = isinstance(row, (list, tuple)) and len(row) in (4, 5)
        if ok:
            suffix, unit, scale, text = row[:4]
            ok = (isinstance(suffix, str) and bool(_IDENTIFIER.match(suffix))
                  and unit in DISPLAY_UNITS and isinstance(scale, (int, float))
                  and math.isfinite(scale) and scale > 0 and isinstance(text, str))
        if not ok:
            raise ModelError(f"{path}: parameter {row!r} of effect {name} is not (suffix, unit, "
                             f"positive scale, description[, dict]){fix}")
        known = _known(row[4], row, path, name) if len(row) == 5 else {}
        out.append((suffix, unit, float(scale), text, known))
    suffixes = [r[0] for r in out]
    if len(set(suffixes)) != len(suffixes):
        raise ModelError(f"{path}: effect {name} declares a parameter suffix twice; give each "
                         f"parameter its own suffix")
    return tuple(out)


def _functions(module, path: str, name: str) -> dict:
    out = {}
    for fname, args in FUNCTIONS.items():
        f = getattr(module, fname, None)
        if f is None:
            continue
        if not callable(f):
            raise ModelError(f"{path}: {fname} of effect {name} is not a function; define "
                             f"def {fname}({', '.join(args)}=None)")
        try:
            inspect.signature(f).bind(*args)
        except TypeError:
            line = getattr(getattr(f, "__code__", None), "co_firstlineno", None)
            where = path + ("" if line is None else f", line {line}")
            raise ModelError(f"{where}: {fname} of effect {name} must accept the arguments "
                             f"({', '.join(args)}=None)") from None
        except ValueError:
            pass
        out[fname] = f
    if not out:
        raise ModelError(f"{path}: effect {name} defines none of {', '.join(FUNCTIONS)}; "
                         f"define at least one (see doe_calib.model.effects.user)")
    return out


def _effect_class(module, path: str) -> type:
    name = getattr(module, "NAME", None)
    if not isinstance(name, str) or not _IDENTIFIER.match(name):
        raise ModelError(f"{path}: NAME must be a word of letters, digits and _, e.g. "
                         f'NAME = "my_effect", got {name!r}')
    per_joint = getattr(module, "PER_JOINT", False)
    if not isinstance(per_joint, bool):
        raise ModelError(f"{path}: PER_JOINT of effect {name} must be True or False, "
                         f"got {per_joint!r}")
    words = {}
    for key, attr in (("PHRASE", "phrase"), ("IMPLAUSIBLE", "implausible_words")):
        text = getattr(module, key, None)
        if text is not None and not isinstance(text, str):
            raise ModelError(f"{path}: {key} of effect {name} must be words, got {text!r}")
        if text is not None:
            words[attr] = text
    attrs = {"name": name, "source": path, "per_joint": per_joint, **words,
             "parameter_specs": _parameter_specs(getattr(module, "PARAMETERS", None), path, name),
             "functions": MappingProxyType(_functions(module, path, name)),
             "__doc__": f"User effect {name} from {path}.", "__module__": module.__name__}
    return type(f"UserEffect_{name}", (UserEffect,), attrs)


def _import(path: str):
    spec = importlib.util.spec_from_file_location(f"doe_calib_user_effect_{Path(path).stem}",
                                                  path)
    if spec is None or spec.loader is None:
        raise DataError("not a Python file; give a .py file declaring NAME, PARAMETERS and "
                        "the effect's functions", path)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        raise DataError(f"Python syntax error ({exc.msg}); correct the file", path,
                        exc.lineno) from None
    except Exception as exc:
        raise DataError(f"running the file raised {type(exc).__name__}: {exc}; fix it so "
                        f"that `python {Path(path).name}` runs", path, _line(exc, path)) from None
    return module


def load_effect_file(path) -> list[type]:
    """Import a user effect file and make its effect class; nothing is registered.

    Parameters
    ----------
    path : str or Path
        A Python file following the protocol of :mod:`doe_calib.model.effects.user`.

    Returns
    -------
    list of type
        The file's :class:`UserEffect` subclass; each call makes a new class from
        the file's current content.

    Raises
    ------
    DataError
        The file is missing or cannot be run (with the line).
    ModelError
        A declaration is missing or wrong. (A name already taken by a built-in
        effect or another file is refused by the registry that would hold both.)
    """
    path = Path(path)
    if not path.is_file():
        raise DataError("no such effect file; give the path of a Python file declaring NAME, "
                        "PARAMETERS and the effect's functions (example: "
                        "doe_calib/examples/example_effect.py)", path)
    source = str(path.resolve())
    return [_effect_class(_import(source), source)]
