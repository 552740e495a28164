"""Margins of the loop as it runs: the sampled plant, the delay and the controller as coded.

Modules (one concept each):

* :mod:`.margins` -- gain margin, phase margin and peak sensitivity of sampled loops;
* :mod:`.loop` -- the interconnection, the two break points, the closed loop's poles;
* :mod:`.controller` -- a controller as coded, linearised (Jacobians of its exported step);
* :mod:`.pid_family` -- the PID family's law at rest in closed form (the tuning's route);
* :mod:`.grid` -- where the margins must hold: stroke, parameter box, friction regime.
"""
