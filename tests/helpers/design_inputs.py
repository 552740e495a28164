"""Inputs of ``fcomp design`` shared by its tests and the hostile-case runner."""

#: A small pneumatic rig (tests/test_design.py, benchmarks/hostile_cases.py).
RIG = """[rig]
bore = 0.032
rod = 0.012
mass = 1.2
orientation = "horizontal"

[limits]
stroke = 0.2
speed_max = 0.2
accel_max = 4.0
pressure_min = 1.5e5
pressure_max = 2.5e5
duration_max = 20.0
rate = 500.0
"""
