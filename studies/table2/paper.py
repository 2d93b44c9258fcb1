"""What the paper reports for its KR 270 elastostatic experiment (Tables II and IV).

Transcribed from ``shared/seed-paper.txt`` (an OCR of the paper).

Table II, as printed, has five values in ten of its fifteen rows and six in
the other five. The six-value rows are rows 2, 5, 8, 11 and 14 — the middle
row of each group of three — and their second column takes five values,
−0.01, −25.24, −56.9, −99.85 and −140 deg, spread over the A2 range: the
paper's "15 configurations with five different angles q2". We read the
table as having q2 in a cell merged over each group of three rows, so a
five-value row is (q1, q3, q4, q5, q6) and takes the q2 of its group. Row 2's
q2 = −0.01 deg lies 4.99 deg outside the A2 limit of our KR 270-class URDF
(−5 deg); the design is evaluated as printed (an information matrix needs no
limit), and the study says so.

Table IV gives the compliances in "rad/N×mm" (OCR); the magnitudes (0.25–3.5)
fit µrad/(N·m) for a robot of this class (A2 stiffness ≈ 3.5 MN·m/rad), which
is how we read them. Relative standard deviations (± / value) do not depend
on this choice.
"""
from __future__ import annotations

import numpy as np

#: q2 of each group of three rows (deg): the merged cell.
Q2_GROUPS_DEG = (-0.01, -25.24, -56.9, -99.85, -140.0)

#: Table II rows as printed (deg): five values = (q1, q3, q4, q5, q6), six = q1 … q6.
TABLE_II_ROWS = (
    (79.20, -5.57, 51.00, -97.52, -91.67),
    (63.00, -0.01, -12.22, -56.49, 41.42, 150.55),
    (63.00, -47.98, -70.04, -61.55, 177.16),
    (95.00, 33.00, 129.69, -98.10, 90.57),
    (95.00, -25.24, -107.01, 109.95, -61.19, 174.21),
    (105.00, 14.30, 55.21, 41.26, -152.97),
    (56.60, 44.54, -55.11, 41.90, 152.06),
    (56.60, -56.9, 64.73, -129.65, -98.260, -90.55),
    (144.80, 104.49, -69.41, 61.67, -6.33),
    (-41.00, -91.68, 55.12, 41.53, -152.48),
    (-143.00, -99.85, -32.64, 110.31, -61.47, -6.29),
    (-143.00, -72.01, 129.65, -98.09, 90.82),
    (133.00, 147.68, 129.64, -97.90, 90.99),
    (-60.00, -140, 7.59, -110.09, -61.36, -174.09),
    (-60.00, -52.00, -124.89, -41.62, 27.78),
)

#: Table IV: identified compliance and its ± (µrad/(N·m)), by the paper's name.
TABLE_IV = {
    "chi2_1": (0.287, 0.0003),
    "chi2_2": (0.277, 0.0004),
    "chi2_3": (0.302, 0.0005),
    "chi2_4": (0.293, 0.0010),
    "chi2_5": (0.246, 0.0007),
    "chi3": (0.416, 0.0011),
    "chi4": (2.786, 0.0071),
    "chi5": (3.483, 0.0120),
    "chi6": (2.074, 0.0267),
}


def paper_design_deg() -> np.ndarray:
    """The paper's 15 configurations q1 … q6 (deg), five-value rows completed from their group."""
    rows = []
    for i, row in enumerate(TABLE_II_ROWS):
        q2 = Q2_GROUPS_DEG[i // 3]
        if len(row) == 6:
            if row[1] != q2:
                raise AssertionError(f"row {i + 1}: q2 {row[1]} is not its group's {q2}")
            rows.append(row)
        else:
            rows.append((row[0], q2) + tuple(row[1:]))
    return np.array(rows, float)
