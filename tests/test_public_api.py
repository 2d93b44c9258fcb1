"""The public names: each importable from ``doe_calib``, each from the module that defines it."""
import importlib
import subprocess
import sys

import pytest

import doe_calib


@pytest.mark.parametrize("name", doe_calib.__all__)
def test_every_public_name_resolves_to_its_definition(name):
    value = getattr(doe_calib, name)
    if name == "examples":
        assert value.__name__ == "doe_calib.examples"
    elif isinstance(value, type) or callable(value) and hasattr(value, "__qualname__"):
        assert value.__module__ == doe_calib._PUBLIC[name], name
    else:  # data (the default model string, the built-in registry): found where listed
        assert getattr(importlib.import_module(doe_calib._PUBLIC[name]), name) is value


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'identfy'"):
        doe_calib.identfy  # noqa: B018


def test_importing_the_package_loads_no_heavy_library():
    code = ("import sys, doe_calib; heavy = [m for m in ('casadi', 'pinocchio', 'cvxpy', "
            "'matplotlib', 'scipy') if m in sys.modules]; print(','.join(heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_model_objects_print_in_one_short_line(model6):
    for obj, words in [(model6.robot, ["kr270_class", "6 joints", "tool0"]),
                       (model6.tool, ["3 markers", "A, B, C"]),
                       (model6, ["joint_offset+geometry+joint_compliance", "69 parameters"]),
                       (model6.description, ["69 parameters"])]:
        text = repr(obj)
        assert "\n" not in text and len(text) < 160, text
        assert all(w in text for w in words), text
