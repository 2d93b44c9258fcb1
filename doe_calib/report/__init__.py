"""Self-contained HTML reports (figures embedded as PNG, no external resources).

:func:`identification_report` shows an identification's parameters,
correlations and residuals; :func:`design_report` a design's poses, their
geometry, the constraints met, the efficiency against the bound and the
predicted standard deviations; :func:`diagnosis_report` and
:func:`refine_report` the verdict, the ranked candidate effects and the error
falling step by step; :func:`compare_report` designs and results side by
side; :func:`augment_report` the poses ``design --augment`` adds to a campaign and what
they add; :func:`write_report` writes any sections built with :mod:`.html`.
Reporting code formats and plots; it computes nothing
the library does not already provide.
"""
from doe_calib.report.augment import augment_report
from doe_calib.report.compare import compare_report
from doe_calib.report.design import design_report, design_sections
from doe_calib.report.diagnosis import diagnosis_report, refine_report, refine_sections
from doe_calib.report.html import write_report
from doe_calib.report.identification import identification_report

__all__ = ["identification_report", "design_report", "diagnosis_report", "refine_report",
           "compare_report", "augment_report", "design_sections", "refine_sections",
           "write_report"]
