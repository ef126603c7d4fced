"""Convergence tables that cannot mislead: coarse-to-fine order by what the key means, the
finest run as reference, a rate only over errors that shrink above the round-off floor,
with its spread; the two misleading studies of the cantilever run through the CLI."""

from __future__ import annotations

import math

import numpy as np
import pytest

from liegroup_int.cli import main
from liegroup_int.studies import (
    convergence_table,
    finer_direction,
    fit_rate_spread,
    fit_table,
    format_fit,
    table_rate,
)

TIP = np.array([0.3, -0.2, 1.0])


def _rows(param, values, errors, steps=1000):
    """Study rows whose final tip is off TIP by ``errors[i]`` along x (0 for the reference)."""
    return [{"run": i, "overrides": {param: v}, "status": "ok", "steps": steps,
             "final": {"tip": (TIP + [e, 0.0, 0.0]).tolist()}} for i, (v, e) in enumerate(zip(values, errors))]


def test_direction_by_meaning():
    assert finer_direction("space.n_ctrl") == finer_direction("space.degree") == 1
    assert finer_direction("integrator.dt") == finer_direction("integrator.rtol") == -1
    assert finer_direction("material.rho", "larger") == 1
    with pytest.raises(ValueError, match="material.rho: cannot tell.*--finer"):
        finer_direction("material.rho")


@pytest.mark.parametrize("order", [[0, 1, 2, 3, 4], [4, 3, 2, 1, 0], [2, 4, 0, 3, 1]])
def test_n_ctrl_study_measured_against_the_finest_mesh_in_any_order(order):
    """Errors C n^-2 against n_ctrl = 161 (error 0): whatever order the values come in, the
    table runs 11, 21, 41, 81 against the 161 run and the rate in 1/n_ctrl is 2 (exactly:
    the synthetic errors lie on the line, so the standard error and the local slopes'
    spread are rounding, < 1e-9)."""
    ns = [11, 21, 41, 81, 161]
    errs = [0.0 if n == 161 else 3.0 * n**-2.0 for n in ns]
    rows = _rows("space.n_ctrl", [ns[i] for i in order], [errs[i] for i in order])
    table = convergence_table(rows, "space.n_ctrl", quantity="tip")
    assert [t["value"] for t in table] == ns[:-1]
    assert {t["reference_run"] for t in table} == {order.index(4)} and table[0]["finer"] == "larger"
    fit = fit_table(table)
    assert abs(fit.rate - 2.0) < 1e-9 and fit.stderr < 1e-9 and abs(fit.local_max - fit.local_min) < 1e-9
    assert fit.values == (11, 21, 41, 81)
    assert format_fit(fit, "space.n_ctrl", "larger").startswith("fitted rate: 2.000 +- ")


def test_non_monotone_errors_give_no_rate_and_name_the_value():
    """The cantilever dt study's errors (7.5e-8, 5.9e-9, 1.4e-8 against dt = 1.25e-7): the
    third does not shrink, so no rate; the line names dt = 2.5e-07 and its neighbour."""
    rows = _rows("integrator.dt", [1e-6, 5e-7, 2.5e-7, 1.25e-7], [7.541e-8, 5.936e-9, 1.399e-8, 0.0])
    table = convergence_table(rows, "integrator.dt", quantity="tip")
    with pytest.raises(ValueError, match=r"integrator.dt = 2.5e-07 gives 1.40e-08, not below 5.94e-09 at 5e-07") as e:
        fit_table(table)
    assert "\n" not in str(e.value)


def test_round_off_entries_only_at_the_fine_end():
    """Errors at relative 1e-13 (below the floor 100 eps sqrt(2000) = 1e-12) are left out
    when they are the finest; three above it still give a rate. A floor entry followed by a
    larger error is named instead."""
    scale = float(np.linalg.norm(TIP))
    dts = [8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4]
    errs = [1e-4, 1.25e-5, 1.5625e-6, 1e-13 * scale, 1e-13 * scale, 0.0]
    table = convergence_table(_rows("integrator.dt", dts, errs), "integrator.dt", quantity="tip")
    assert [t["round_off"] for t in table] == [False, False, False, True, True]
    assert table_rate(table) == pytest.approx(3.0, abs=1e-9)
    errs[1] = 1e-13 * scale
    table = convergence_table(_rows("integrator.dt", dts, errs), "integrator.dt", quantity="tip")
    with pytest.raises(ValueError, match="integrator.dt = 0.004 is within 100x of the round-off floor"):
        fit_table(table)


def test_spread_is_the_slope_standard_error():
    """On scattered points, the standard error equals numpy's covariance estimate of the
    slope (same n - 2 degrees of freedom) and the local slopes bracket the fit."""
    rng = np.random.default_rng(7)
    h = np.array([0.1, 0.05, 0.025, 0.0125, 0.00625])
    e = 2.0 * h**4 * np.exp(rng.normal(0.0, 0.2, h.size))
    slope, stderr, lo, hi = fit_rate_spread(h, e)
    p, cov = np.polyfit(np.log(h), np.log(e), 1, cov=True)
    assert math.isclose(slope, p[0], rel_tol=1e-12) and math.isclose(stderr, math.sqrt(cov[0, 0]), rel_tol=1e-9)
    assert lo < slope < hi and 0.0 < stderr < 0.5


def _converge(capsys, tmp_path, param, values, *sets):
    argv = ["converge", "cantilever", "--param", param, "--values", *values, "--serial", "--out", str(tmp_path)]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 0
    return capsys.readouterr().out


def test_cli_n_ctrl_study_in_scrambled_order(capsys, tmp_path):
    """Values 41 11 21: the errors are against the n_ctrl = 41 run (the finest), listed 11
    then 21, whatever the order given."""
    out = _converge(capsys, tmp_path, "space.n_ctrl", ["41", "11", "21"], "integrator.dt=auto", "t_end=0.002")
    lines = out.splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("errors, coarse to fine"))
    assert "against the finest run (run 0; larger space.n_ctrl is finer)" in lines[head]
    assert lines[head + 1].startswith("  space.n_ctrl = 11: error") and lines[head + 2].startswith("  space.n_ctrl = 21:")
    assert "no rate fitted: 2 usable errors" in out


def test_cli_non_monotone_dt_study_fits_no_rate(capsys, tmp_path):
    """The cantilever dt study (gauss-p quadrature, t_end = 1.75e-3): the error at dt = 2.5e-7
    is not below the one at 5e-7 (measured 1.0e-8, 9.2e-10, 1.4e-9 against dt = 1.25e-7), so
    the CLI prints no rate and names both values."""
    out = _converge(capsys, tmp_path, "integrator.dt", ["1e-6", "5e-7", "2.5e-7", "1.25e-7"], "t_end=0.00175",
                    "space.quadrature=gauss-p")
    assert "fitted rate" not in out
    line = next(ln for ln in out.splitlines() if ln.startswith("no rate fitted"))
    assert "integrator.dt = 2.5e-07 gives" in line and "at 5e-07" in line


def test_cli_unknown_direction_refused(capsys, tmp_path):
    assert main(["converge", "heavy_top", "--param", "body.mass", "--values", "1", "2", "--serial",
                 "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--finer larger|smaller" in err and "body.mass" in err
    assert not (tmp_path / "s").exists()


def test_a_rate_below_the_method_order_gets_a_note(capsys, tmp_path):
    """The same cantilever study on the gauss-spline quadrature: the errors shrink (measured
    6.6e-9, 4.2e-9, 1.2e-9; a rate is fitted, 1.26 +- 0.35) but RKMK4 is of order 4: steps
    near the stability limit, where the fastest modes excited by the suddenly applied load
    set the error. The CLI says so in a line under the rate. (Which of these errors shrink
    varies with t_end: over t_end = 5e-3 gauss-spline gives 2.10 +- 0.33, while on gauss-p
    and on the default gauss-spline-reduced rule the errors do not shrink.)"""
    out = _converge(capsys, tmp_path, "integrator.dt", ["1e-6", "5e-7", "2.5e-7", "1.25e-7"], "t_end=0.00175",
                    "space.quadrature=gauss-spline")
    lines = out.splitlines()
    rate = next(ln for ln in lines if ln.startswith("fitted rate"))
    note = lines[lines.index(rate) + 1]
    assert note.startswith("note: the fitted rate") and "rkmk4's order 4" in note and "asymptotic range" in note


def test_order_note_rules():
    """No note within 0.5 (or three standard errors) of the order; a note below or above it;
    none for an unknown method."""
    from liegroup_int.studies import RateFit, order_note

    fit = lambda rate, se=0.05: RateFit(rate, se, rate, rate, (1, 2, 3))  # noqa: E731
    assert order_note(fit(3.7), "rkmk4") is None and order_note(fit(2.0, 0.7), "rkmk4") is None
    assert "not rkmk4's order 4" in order_note(fit(2.1), "rkmk4")
    assert "faster than the method's order" in order_note(fit(5.2), "rkmk4")
    assert order_note(fit(2.0), "no-such-method") is None and order_note(fit(2.0), None) is None
