"""The noncentral χ² survival function and power noncentrality equal SciPy's."""
import pytest
from fresh_interpreter import run_python
from scipy import optimize
from scipy.special import chdtri, chndtr
from scipy.stats import ncx2

from doe_calib.estimation.chi_square import chi2_survival, chi2_upper_quantile
from doe_calib.estimation.noncentral_chi_square import (noncentral_chi2_survival,
                                                        noncentrality_for_power)


@pytest.mark.parametrize("dof", [1, 2, 3, 5, 12, 30])
def test_survival_is_scipy_ncx2(dof):
    for nc in (0.0, 0.1, 1.0, 5.0, 10.0, 30.0, 100.0, 500.0):
        for x in (0.01, 0.5, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0):
            ref = float(ncx2.sf(x, dof, nc)) if nc > 0 else chi2_survival(x, dof)
            if ref > 1e-12:  # below, SciPy's 1 − cdf is itself only a few digits
                assert noncentral_chi2_survival(x, dof, nc) == pytest.approx(ref, rel=1e-10)


def test_noncentrality_zero_is_the_central_distribution():
    for dof in (1, 4, 9):
        for x in (0.3, 4.0, 20.0):
            assert noncentral_chi2_survival(x, dof, 0.0) == pytest.approx(
                chi2_survival(x, dof), rel=1e-15)


@pytest.mark.parametrize("dof", [1, 2, 3, 6, 12, 40])
@pytest.mark.parametrize("power", [0.5, 0.8, 0.95])
def test_noncentrality_for_power_is_scipy_root(dof, power):
    critical = chdtri(dof, 0.05)
    assert chi2_upper_quantile(0.05, dof) == pytest.approx(critical, rel=1e-13)
    f = lambda lam: 1.0 - chndtr(critical, dof, lam) - power  # noqa: E731
    ref = optimize.brentq(f, 0.0, 1e4, xtol=1e-13, rtol=1e-15)
    lam = noncentrality_for_power(dof, 0.05, power)
    assert lam == pytest.approx(ref, rel=1e-11)
    assert noncentral_chi2_survival(critical, dof, lam) == pytest.approx(power, rel=1e-12)


def test_one_dof_power_is_the_normal_shift():
    # one degree of freedom: λ = (z_{1−α/2} + z_power)²
    from statistics import NormalDist

    z = NormalDist().inv_cdf
    assert noncentrality_for_power(1, 0.05, 0.8) == pytest.approx(
        (z(0.975) + z(0.8)) ** 2, rel=2e-4)  # the one-sided shift neglects the far tail
    assert noncentrality_for_power(3, 0.05, 0.04) == 0.0
    with pytest.raises(ValueError):
        noncentral_chi2_survival(1.0, 3, -1.0)


def test_diagnosis_loads_no_scipy():
    """A diagnosis's tests and detectabilities no longer pull in scipy.special/optimize
    (0.4–0.5 s to import, a quarter of a whole ``diagnose``)."""
    code = ("import sys\n"
            "import doe_calib.diagnosis, doe_calib.design.detectability\n"
            "from doe_calib.estimation.noncentral_chi_square import noncentrality_for_power\n"
            "print(noncentrality_for_power(2, 0.05, 0.8))\n"
            "bad = sorted(m for m in sys.modules if m.startswith(('scipy.special', "
            "'scipy.optimize', 'scipy.stats')))\n"
            "assert not bad, bad[:5]\n")
    assert float(run_python(code)) == pytest.approx(9.6347, abs=1e-4)
