"""Self-contained HTML reports (figures embedded as PNG, no external resources).

:func:`identification_report` shows an identification's parameters,
correlations and residuals; :func:`design_report` a design's poses, their
geometry, the constraints met, the efficiency against the bound and the
predicted standard deviations; :func:`diagnosis_report` and
:func:`refine_report` the verdict, the ranked candidate effects and the error
falling step by step; :func:`compare_report` designs and results side by
side; :func:`augment_report` the poses ``design --augment`` adds to a campaign and what
they add; :func:`write_report` writes any sections built with :mod:`.html`;
:mod:`.notebook` gives each result type its ``_repr_html_`` (a notebook's view).
Reporting code formats and plots; it computes nothing
the library does not already provide.
"""
from doe_calib.runtime.lazy_exports import lazy_exports

#: Public name → the module of this package that defines it. Each is imported on first
#: use, so that ``from doe_calib.report.figures import …`` (the diagnose command's residual
#: figure) does not load every report and matplotlib's 3-D toolkit first.
_HOMES = {"identification_report": "identification", "design_report": "design",
          "design_sections": "design", "diagnosis_report": "diagnosis",
          "refine_report": "diagnosis", "refine_sections": "diagnosis",
          "compare_report": "compare", "augment_report": "augment", "write_report": "html"}

__all__ = list(_HOMES)


__getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
