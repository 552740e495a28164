"""Helpers of the test suite (not tests themselves).

* :mod:`helpers.reference_lugre` -- the LuGre-family equations written out
  plainly, integrated by SciPy: the independent reference of the model tests;
* :mod:`helpers.independent_plants` -- the plants' equations written again in
  plain Python, for the plant tests;
* :mod:`helpers.browser` -- the shared ``fcomp study all --fast`` site and a
  headless Chromium that renders its reports;
* :mod:`helpers.import_graph` -- the module graph of the checkout and its
  import cycles (the architecture test).
"""
