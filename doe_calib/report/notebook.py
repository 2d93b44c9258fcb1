"""Results in a notebook: each result type's ``_repr_html_``, given by the report.

A result holds data and never imports the report that draws it (the report is the
higher layer). Here the report gives each result class with an HTML view its
``_repr_html_`` when the class's module is first imported, so a result shows as its
report fragment in Jupyter however it was made (``doe_calib.load``,
``doe_calib.identify``, ``from doe_calib.estimation.identify import identify``),
and ``import doe_calib`` imports no result module (``doe-calib --help`` stays light).
``doe_calib/__init__.py`` calls :func:`watch` once.
"""
from __future__ import annotations

import sys
from importlib import import_module

#: Module of a result class → (the class, report module, function drawing it as HTML).
VIEWS = {
    "doe_calib.estimation.result": ("IdentificationResult", "identification", "result_html"),
    "doe_calib.diagnosis.result": ("DiagnosisResult", "diagnosis", "diagnosis_html"),
    "doe_calib.diagnosis.refine_result": ("RefineResult", "diagnosis", "refine_html"),
    "doe_calib.design.result": ("DesignResult", "design", "design_fragment"),
    "doe_calib.design.augment_result": ("AugmentResult", "augment", "augment_fragment"),
    "doe_calib.design.comparison": ("Comparison", "compare", "compare_fragment"),
}


def _view(report: str, function: str):
    def _repr_html_(self) -> str:
        """This result as its report's HTML fragment, no page chrome (what Jupyter shows)."""
        return str(getattr(import_module(f"doe_calib.report.{report}"), function)(self))

    return _repr_html_


def attach(module) -> None:
    """Give the result class of ``module`` (a key of :data:`VIEWS`) its ``_repr_html_``."""
    name, report, function = VIEWS[module.__name__]
    getattr(module, name)._repr_html_ = _view(report, function)


class _AttachAfter:
    """A result module's own loader, then :func:`attach`."""

    def __init__(self, loader):
        self.loader = loader

    def create_module(self, spec):
        return self.loader.create_module(spec)

    def exec_module(self, module):
        self.loader.exec_module(module)
        attach(module)

    def __getattr__(self, name):  # get_source, get_filename, … of the loader it wraps
        return getattr(self.loader, name)


class _ResultModules:
    """Finds the modules of :data:`VIEWS` with the finders after it, wrapping their loader."""

    def find_spec(self, name, path, target=None):
        if name not in VIEWS:
            return None
        for finder in sys.meta_path[sys.meta_path.index(self) + 1:]:
            spec = finder.find_spec(name, path, target) if hasattr(finder, "find_spec") else None
            if spec is not None and spec.loader is not None:
                spec.loader = _AttachAfter(spec.loader)
                return spec
        return None


def watch() -> None:
    """Attach the views of the result modules imported so far, and of each imported later."""
    if not any(isinstance(f, _ResultModules) for f in sys.meta_path):
        sys.meta_path.insert(0, _ResultModules())
    for name in VIEWS:
        if name in sys.modules:
            attach(sys.modules[name])
