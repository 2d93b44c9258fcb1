"""The noncentrality at which a χ² test has a given power is the root of SciPy's power equation."""
import pytest
from scipy import optimize
from scipy.special import chdtri, chndtr

from doe_calib.estimation.chi_square import chi2_upper_quantile, noncentrality_for_power


@pytest.mark.parametrize("dof", [1, 2, 3, 6, 12, 40])
@pytest.mark.parametrize("power", [0.5, 0.8, 0.95])
def test_noncentrality_for_power_is_scipy_root(dof, power):
    critical = chdtri(dof, 0.05)
    assert chi2_upper_quantile(0.05, dof) == pytest.approx(critical, rel=1e-13)
    f = lambda lam: 1.0 - chndtr(critical, dof, lam) - power  # noqa: E731
    ref = optimize.brentq(f, 0.0, 1e4, xtol=1e-13, rtol=1e-15)
    lam = noncentrality_for_power(dof, 0.05, power)
    assert lam == pytest.approx(ref, rel=1e-11)
    assert 1.0 - chndtr(critical, dof, lam) == pytest.approx(power, rel=1e-12)


def test_one_dof_power_is_the_normal_shift():
    # one degree of freedom: λ = (z_{1−α/2} + z_power)²
    from statistics import NormalDist

    z = NormalDist().inv_cdf
    assert noncentrality_for_power(1, 0.05, 0.8) == pytest.approx(
        (z(0.975) + z(0.8)) ** 2, rel=2e-4)  # the one-sided shift neglects the far tail
    assert noncentrality_for_power(3, 0.05, 0.04) == 0.0
