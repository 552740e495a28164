"""Compare, diagnose, add the missing effect, watch the error fall (issue 5).

The pieces, one concept per module:

* :mod:`.data` -- experiments, signals, the force to match, data scales;
* :mod:`.regimes` -- pre-sliding / reversal / sliding / dwell-break-away;
* :mod:`.split` -- held-out splits by experiment or contiguous segment;
* :mod:`.noise` -- the noise floor and effective sample sizes;
* :mod:`.refit` -- fits on training samples, predictions everywhere;
* :mod:`.compare` -- errors per regime, worst segments, plant domain;
* :mod:`.features` -- residual features and their held-out strength;
* :mod:`.catalogue` -- candidates, signatures, data-driven starts;
* :mod:`.loop` -- :class:`Diagnosis`, the add / refit / score loop;
* :mod:`.report` -- the self-contained HTML report.

>>> from fcomp.diagnosis import Diagnosis                       # doctest: +SKIP
>>> d = Diagnosis("lugre").fit(measurement)                     # doctest: +SKIP
>>> d.added_, d.verdict_, d.rms_baseline_, d.rms_final_         # doctest: +SKIP
"""

from fcomp.diagnosis.compare import Comparison, compare
from fcomp.diagnosis.data import DiagnosisData, prepare
from fcomp.diagnosis.loop import Candidate, Diagnosis, Step
from fcomp.diagnosis.residuals import regime_errors

__all__ = ["Candidate", "Comparison", "Diagnosis", "DiagnosisData", "Step", "compare",
           "prepare", "regime_errors"]
