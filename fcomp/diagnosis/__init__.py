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
* :mod:`.rule` -- the acceptance rule, a frozen value judging two fits;
* :mod:`.workers` -- the candidate refits on an executor handed in;
* :mod:`.search` -- the steps: add, refit, judge; :mod:`.revision` -- the
  checks after them (backward, swaps, confounded partners);
* :mod:`.verdict` -- structure left in the final residual, as data;
* :mod:`.result` -- the frozen :class:`~.result.DiagnosisResult`;
* :mod:`.wording` -- the sentences of the rule and the verdict;
* :mod:`.writers` -- the JSON and the model file; :mod:`.report`,
  :mod:`.figures` -- the self-contained HTML report and its figures;
* :mod:`.loop` -- :class:`Diagnosis`: the configuration, and the pipeline
  data -> search -> result -> baseline check.

>>> from fcomp.diagnosis import Diagnosis                       # doctest: +SKIP
>>> d = Diagnosis("lugre").fit(measurement)                     # doctest: +SKIP
>>> d.added_, d.verdict_, d.rms_baseline_, d.rms_final_         # doctest: +SKIP
"""

from fcomp.diagnosis.compare import Comparison, compare
from fcomp.diagnosis.data import DiagnosisData, prepare
from fcomp.diagnosis.loop import Candidate, Diagnosis, DiagnosisConfig, Step
from fcomp.diagnosis.residuals import regime_errors
from fcomp.diagnosis.result import DiagnosisResult
from fcomp.diagnosis.rule import AcceptanceRule
from fcomp.diagnosis.verdict import VerdictRule

__all__ = ["AcceptanceRule", "Candidate", "Comparison", "Diagnosis", "DiagnosisConfig",
           "DiagnosisData", "DiagnosisResult", "Step", "VerdictRule", "compare", "prepare",
           "regime_errors"]
