"""Results in a notebook: each result type's ``_repr_html_``, given by the report.

A result holds data and never imports the report that draws it (a higher layer). The
report gives each result class with an HTML view its ``_repr_html_`` as the class's
module is imported, so a result shows as its report fragment in Jupyter however it was
made (``doe_calib.load``, ``from doe_calib.estimation.identify import identify``), and
``import doe_calib`` imports no result module. ``doe_calib/__init__.py`` calls :func:`watch`.
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


class _AttachAfter:
    """A result module's own loader, then its class's view attached."""

    def __init__(self, loader):
        self.loader = loader

    def __getattr__(self, name):  # create_module, get_source, … of the loader it wraps
        return getattr(self.loader, name)

    def exec_module(self, module):
        self.loader.exec_module(module)
        name, report, function = VIEWS[module.__name__]

        def _repr_html_(result) -> str:
            """This result as its report's HTML fragment, no page chrome (what Jupyter shows)."""
            return str(getattr(import_module(f"doe_calib.report.{report}"), function)(result))

        getattr(module, name)._repr_html_ = _repr_html_


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
    """Attach each view as its result module is imported (from here on)."""
    sys.meta_path.insert(0, _ResultModules())
