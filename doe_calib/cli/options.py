"""Option values checked where they enter: numbers in range, output paths that can be written.

Number converters are argparse ``type=`` functions that raise
:class:`~doe_calib.errors.OptionError` naming the option, so a bad value stops
the command before any work with one line (``error: --sigma -1: ...``); the
range checks are the library's own (:mod:`doe_calib.io.setting_ranges`), so an
option and the keyword argument it becomes refuse the same values.

Each command module may declare ``OUTPUTS``: option destination → ``"file"``
(written as given: its folder must exist), ``"folder"`` (created if needed:
its nearest existing ancestor must be a writable folder) or ``"file or folder"``
(a file when the path has a suffix and is not an existing folder, else a folder).
:func:`check_outputs` checks them all before the command runs, and refuses an output file that is
one of the command's input files (any option naming an existing file: data,
URDF, tool, design, result …), compared as resolved paths (symlinks,
relative paths and hard links).
"""
from __future__ import annotations

import math
import os
import re
from pathlib import Path

from doe_calib.errors import OptionError
from doe_calib.io import setting_ranges as ranges


def _converter(option: str, kind, what: str, check, *args):
    def convert(text: str):
        try:
            value = kind(text)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise OptionError(f"{option} {text!r}: expected {what}")
        return check(option, value, *args)
    return convert


def positive(option: str, unit: str):
    """A ``type=`` converter: a finite number > 0 in ``unit`` (e.g. ``--sigma`` in mm)."""
    return _converter(option, float, f"a positive number in {unit}", ranges.positive, unit)


def at_least(option: str, minimum: float, unit: str = ""):
    """A ``type=`` converter: a finite number ≥ ``minimum`` (e.g. ``--dwell`` ≥ 0 s)."""
    said = f" {unit}" if unit else ""
    return _converter(option, float, f"a number of {minimum:g}{said} or more", ranges.at_least,
                      minimum, unit)


def probability(option: str):
    """A ``type=`` converter: a probability strictly between 0 and 1 (e.g. ``--level``)."""
    return _converter(option, float, "a probability between 0 and 1", ranges.probability)


def fraction(option: str):
    """A ``type=`` converter: a fraction from 0 to 1, 1 excluded (e.g. ``--min-gain``)."""
    return _converter(option, float, "a fraction from 0 to 1", ranges.fraction)


def count(option: str, minimum: int = 1, what: str = ""):
    """A ``type=`` converter: an integer ≥ ``minimum`` (e.g. ``--poses``)."""
    said = f" {what}" if what else ""
    return _converter(option, int, f"a whole number of {minimum}{said} or more", ranges.whole,
                      minimum, what)


def _option_name(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def _check_file(option: str, path: Path) -> None:
    if path.is_dir():
        raise OptionError(f"{option} {path}: is a folder; give a file name")
    folder = path.parent
    if not folder.is_dir():
        raise OptionError(f"{option} {path}: the folder {folder} does not exist "
                          f"(create it first)" if not folder.exists() else
                          f"{option} {path}: {folder} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK) or \
            (path.exists() and not os.access(path, os.W_OK)):
        raise OptionError(f"{option} {path}: cannot write there (permission denied)")


def _check_folder(option: str, path: Path) -> None:
    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise OptionError(f"{option} {path}: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise OptionError(f"{option} {path}: cannot write in {existing} (permission denied)")


def input_files(args, outputs: dict) -> dict:
    """Every existing file an option names, other than the outputs: resolved path → option."""
    found = {}
    for dest, value in vars(args).items():
        if dest in outputs:
            continue
        for v in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(v, (str, os.PathLike)) and str(v) and Path(v).is_file():
                found.setdefault(os.path.realpath(v), f"{_option_name(dest)} {v}")
    return found


def refuse_input(option: str, path, inputs: dict) -> None:
    """Raise when the output ``path`` is one of ``inputs`` (resolved path → what it is).

    Raises
    ------
    OptionError
        Writing ``path`` would replace an input file.
    """
    key = os.path.realpath(path)
    for other, what in inputs.items():
        if key == other or (Path(path).is_file() and os.path.samefile(path, other)):
            raise OptionError(f"{option} {path}: is the input {what}; writing it would replace "
                              "that file: give the output another name")


def check_outputs(args, outputs: dict) -> None:
    """Check, before any work, that every output option given can be written.

    Parameters
    ----------
    args : argparse.Namespace
    outputs : dict
        Option destination (``"out"``, ``"truth_out"``) → ``"file"``, ``"folder"`` or
        ``"file or folder"``.

    Raises
    ------
    OptionError
        A file in a missing folder or under a file, a folder given for a file,
        a place without write permission, two options naming one file, or an
        output file that is an input file.
    """
    seen, inputs = {}, input_files(args, outputs)
    for dest, kind in outputs.items():
        value = getattr(args, dest, None)
        if value is None:
            continue
        option, path = _option_name(dest), Path(value)
        if kind == "file or folder":
            kind = "file" if path.suffix and not path.is_dir() else "folder"
        (_check_file if kind == "file" else _check_folder)(option, path)
        if kind == "file":
            refuse_input(option, path, inputs)
        key = os.path.abspath(path)
        if key in seen:
            raise OptionError(f"{option} {value}: the same file as {seen[key]}; "
                              f"give each output its own name")
        seen[key] = option


_NEGATIVE = re.compile(r"^-\.?\d")


def join_negative_values(argv) -> list:
    """``--tracker -300,200,0`` as ``--tracker=-300,200,0``: argparse reads a value that
    starts with '-' (other than a plain number) as an option; a long option without ``=``
    followed by a word that starts like a negative number takes it as its value."""
    out = []
    for word in map(str, argv):
        if out and _NEGATIVE.match(word) and out[-1].startswith("--") and "=" not in out[-1]:
            out[-1] = f"{out[-1]}={word}"
        else:
            out.append(word)
    return out
