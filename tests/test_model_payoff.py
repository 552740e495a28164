"""A better model pays off (issue 39 item 4): the matrix of :mod:`controllers.payoff`.

Whether the true model pays off is measured by ``benchmarks/bench_model_payoff.py``
(docs/compensators.md, "Does a better model pay off?"): with the tuning derived on the
loop as it runs it does not hold on every row (the hydraulic servo's pid-ff on `steps`,
the axis50 observer and EKF on a pressure-dependent seal level with plain LuGre), so it is
not asserted here. Asserted: where a structure makes the comparison impossible -- the
LuGre observer cannot be built on a static map -- the row says so and is not counted.
"""

from __future__ import annotations

from controllers.payoff import payoff_rows


def test_a_structure_that_cannot_compare_says_why() -> None:
    """The LuGre observer on a Coulomb-viscous model: not a failed comparison but none."""
    (row,) = [r for r in payoff_rows("hydraulic", ["lugre"], ("lugre-observer",),
                                     ("steps",), samples=0, workers=1)
              if r["wrong"] == "coulomb-viscous"]
    assert row["ok"] is None and "bristle state z" in row["note"]
    assert all(v is None for v in row["per_task"].values())
