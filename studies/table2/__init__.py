"""The paper's Table II: its 15 elastostatic poses against an optimised design (KR 270 class).

``python -m studies.table2 --out results`` or ``doe-calib study table2``
writes ``results/table2.{json,md,png}``. See :mod:`.paper` for how the
printed table is read and :mod:`.study` for the model.
"""
