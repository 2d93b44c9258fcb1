"""A read-only 2-D array with named rows and columns: ``cov_params()`` and ``conf_int()``.

statsmodels answers these with a pandas DataFrame indexed by the parameter names;
pandas is optional here, so this small object carries the names instead.
``np.asarray(m)`` gives the array; ``m["dq_a2", "dq_a3"]`` one element by names
(a joint written as model strings write it, ``dq_j2``; also ``m.loc[…]``);
``m["dq_a2"]`` one row; ``m.to_dataframe()`` the DataFrame.
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import OptionError
from doe_calib.model.parameter_names import resolve


def read_only(array, dtype=float) -> np.ndarray:
    """A copy of ``array`` that cannot be written (``flags.writeable`` False)."""
    out = np.array(array, dtype)
    out.flags.writeable = False
    return out


class Labelled:
    """``values`` (R, C), read-only, with ``rows`` (R names) and ``columns`` (C names).

    ``joints``: the robot's joint names, so that a row or column named by a parameter
    may write its joint as a model string does (:mod:`~doe_calib.model.parameter_names`).
    An integer or slice key indexes the array by position.
    """

    def __init__(self, values, rows, columns, joints=()):
        self.values = read_only(values)
        self.rows, self.columns, self.joints = tuple(rows), tuple(columns), tuple(joints)

    def __array__(self, dtype=None, copy=None):
        if copy or dtype is not None:  # np.array(m), or another dtype: a writeable copy
            return np.array(self.values, dtype)
        return self.values

    @property
    def shape(self) -> tuple:
        return self.values.shape

    def __len__(self) -> int:
        return len(self.values)

    def _at(self, key, names):
        if not isinstance(key, str):
            return key
        found = resolve(key, names, self.joints)
        if found is None:
            raise OptionError(f"no row or column named {key!r}; names: {', '.join(names)}")
        return names.index(found)

    def __getitem__(self, key):
        if isinstance(key, tuple):
            return self.values[self._at(key[0], self.rows), self._at(key[1], self.columns)]
        return self.values[self._at(key, self.rows)]

    @property
    def loc(self) -> "Labelled":
        """``m.loc[row, column]`` as pandas writes it: ``m[row, column]``."""
        return self

    def to_dataframe(self):
        """A pandas DataFrame indexed by the names (needs pandas)."""
        import pandas as pd

        return pd.DataFrame(self.values, index=list(self.rows), columns=list(self.columns))

    def __repr__(self) -> str:
        width = max(map(len, self.rows + ("",)))
        lines = [" " * width + "".join(f"{c:>14}" for c in self.columns)]
        lines += [f"{r:<{width}}" + "".join(f"{v:14.6g}" for v in row)
                  for r, row in zip(self.rows, self.values)]
        return "\n".join(lines)
