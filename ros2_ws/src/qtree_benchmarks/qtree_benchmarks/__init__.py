"""Benchmarks, references, reports and tools of qtree-tamp (no node imports this package).

* :mod:`.task`: the paper's Tables 1-3 (runner, variants, summaries, plots, README table), the
  scale benchmark, the clutter generator's solvability check and the replanning benchmark.
* :mod:`.motion`: the motion-planner benchmark (answers, peers, figures, verification), the
  false-infeasible reference planner and the execution benchmark.
* :mod:`.demo_goal`, :mod:`.soak`: the demo's goal client and the soak of the test suite.
* :mod:`.cli`: every command of ``scripts/`` (each script is a thin entry point over one module).
"""
