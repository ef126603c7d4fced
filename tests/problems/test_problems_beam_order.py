"""Time order of RKMK2/3/4/6 on the paper's pendulum (p=4, n_ctrl=31).

Errors are measured on the velocity control values at the final time, against RKMK6 at
|lambda|max h = 0.1 (see ``references``). Each method is fitted over three steps in its
asymptotic range (docs/theory.md section 4): |lambda|max h <= 0.3, except RKMK6, whose error at
h <= 0.3/|lambda| is below the velocity round-off floor (~2e-10: second derivatives of positions amplify the
rounding of c); it is fitted at |lambda| h in [0.3, 0.6], where its weak growth
(1.3e-3 y^8 per step) changes amplitudes by < 12% over the run. The explicit midpoint rule
(growth y^4/8 per step) and Kutta's RK3 (damping y^4/24 per step) saturate the top modes
over long runs, so they are fitted over 0.01 s; RKMK4 and RKMK6 over 0.1 s.
RKMK2 is fitted at |lambda| h = 0.15..0.0375. Measured slopes: 2.08, 2.91, 4.02, 6.03
(primal) and 2.03, 3.09, 3.87, 5.98 (Galerkin; RKMK4 and RKMK6 over 0.3 s, see
GALERKIN_CASES).
"""

import numpy as np
import pytest

from liegroup_int.integrators import integrate_fixed, resolve_method, spectral_radius
from liegroup_int.scenes import load_scene
from liegroup_int.scenes.beam import problem

# method -> (order, t_end, |lambda| h values)
CASES = {
    "rkmk2": (2, 0.01, [0.15, 0.075, 0.0375]),
    "rkmk3": (3, 0.01, [0.3, 0.15, 0.075]),
    "rkmk4": (4, 0.1, [0.3, 0.2, 0.15]),
    "rkmk6": (6, 0.1, [0.6, 0.42, 0.3]),
}


#: The Galerkin pendulum's RKMK4 and RKMK6 errors over 0.1 s decay faster than their order
#: (local slopes 4.9/4.7 and 6.9/7.0: the top modes' start-up error still dominates); over
#: 0.3 s they are asymptotic (local slopes 3.82, 3.99, 4.01 at |lambda| h = 0.3 .. 0.1 and
#: 6.01, 5.91 at 0.6 .. 0.3).
GALERKIN_CASES = {"rkmk4": (4, 0.3, [0.3, 0.2, 0.15]), "rkmk6": (6, 0.3, [0.6, 0.42, 0.3])}


@pytest.fixture(scope="module", params=["primal", "galerkin"])
def pendulum(request):
    pb = problem(load_scene("pendulum", {"space.degree": 4, "space.n_ctrl": 31, "space.formulation": request.param}))
    y0 = pb.initial_state()
    return pb, y0, spectral_radius(pb, 0.0, y0)


@pytest.fixture(scope="module")
def references(pendulum):
    """RKMK6 at |lambda| h = 0.1, one run with outputs at every fitted T. Its truncation error
    is ~(0.1/0.3)^6 = 1.4e-3 of the smallest fitted error (RKMK6 at |lambda| h = 0.3). Measured:
    it differs from RKMK6 at |lambda| h = 0.05 by 5.9e-11 .. 2.7e-10 (both formulations, all T),
    the velocity round-off floor (RKMK6 at |lambda| h = 0.05 restarted at 0.01 s differs from
    the unbroken run by up to 4e-10)."""
    pb, y0, lam = pendulum
    Ts = (0.01, 0.1, 0.3) if pb.formulation == "galerkin" else (0.01, 0.1)
    out = []  # (t, v) at t = 0 and at every T
    integrate_fixed(pb, resolve_method("rkmk6"), (0.0, Ts[-1]), y0, 0.1 / lam, t_out=Ts,
                    observer=lambda t, y: out.append((t, y.v.copy())))
    assert np.allclose([t for t, _ in out], (0.0,) + Ts, rtol=0, atol=1e-12)
    return {T: v for T, (_, v) in zip(Ts, out[1:])}


@pytest.mark.parametrize("method", sorted(CASES))
def test_pendulum_time_order(method, pendulum, references):
    pb, y0, lam = pendulum
    order, T, ys = GALERKIN_CASES.get(method, CASES[method]) if pb.formulation == "galerkin" else CASES[method]
    hs = np.array(ys) / lam
    errs = [np.abs(integrate_fixed(pb, resolve_method(method), (0.0, T), y0, h)[1].v - references[T]).max() for h in hs]
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    print(f"{method} ({pb.formulation}): |lambda| h = {ys}, errors {['%.3g' % e for e in errs]}, fitted order {slope:.3f}")
    # the velocity round-off floor is ~2e-10 (RKMK6 at any small step differs by that)
    assert min(errs) > 1e-9, "errors too close to the round-off floor to fit an order"
    assert abs(slope - order) < 0.3
