"""A better model pays off (issue 39 item 4): fast slices of the matrix of
:mod:`controllers.payoff` (the whole matrix: ``benchmarks/bench_model_payoff.py``).

Each slice runs a true friction on a plant -- the built-in hydraulic and
pneumatic servos and the plant file ``docs/examples/axis50.toml`` -- and every
model-based compensator built on the true model and on a wrong one, on two fast
tasks and a few robustness draws, and asserts the relation, not today's
numbers: on the median task the true model tracks at least as well, and it is
better in most draws. Where a structure makes the comparison impossible -- the
LuGre observer cannot be built on a static map -- the row says so and is not
counted.
"""

from __future__ import annotations

import pytest

from controllers.payoff import CONTROLLERS, payoff_rows

#: (plant, truth, robustness draws): one truth on each plant.
SLICES = [
    ("hydraulic", "lugre", 3),
    ("pneumatic", "nmlgm", 3),
    ("axis50", "lugre+pressure", 3),
]
TASKS = ("steps", "slow-sine")


@pytest.fixture(scope="module", params=SLICES, ids=lambda s: f"{s[0]}-{s[1]}")
def rows(request: pytest.FixtureRequest) -> list[dict]:
    plant, truth, samples = request.param
    return payoff_rows(plant, [truth], CONTROLLERS, TASKS, samples=samples, workers=2)


@pytest.mark.slow
def test_the_true_model_pays_off(rows: list[dict]) -> None:
    """Every model-based compensator on the true model: median-task ratio <= 1 against each
    wrong model, and better in most robustness draws."""
    assert {r["controller"] for r in rows} == set(CONTROLLERS)
    judged = [r for r in rows if r["ok"] is not None]
    assert judged
    bad = [f"{r['plant']}/{r['truth']}: {r['controller']} vs {r['wrong']}: median "
           f"{r['median']}, tasks {r['per_task']}, better in {r['true_better_in']} of "
           f"{r['draws']} draws" for r in judged if not r["ok"]]
    assert not bad, "\n".join(bad)
    for r in judged:
        assert r["true_better_in"] is not None and r["true_better_in"] > 0.5


def test_a_structure_that_cannot_compare_says_why() -> None:
    """The LuGre observer on a Coulomb-viscous model: not a failed comparison but none."""
    (row,) = [r for r in payoff_rows("hydraulic", ["lugre"], ("lugre-observer",),
                                     ("steps",), samples=0, workers=1)
              if r["wrong"] == "coulomb-viscous"]
    assert row["ok"] is None and "bristle state z" in row["note"]
    assert all(v is None for v in row["per_task"].values())
