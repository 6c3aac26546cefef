"""Benchmark of the Q-Tree policies (Tables 1-3, Figures 4-5 of the paper), as importable modules.

``scripts/benchmark.py`` is the entry point. Modules: :mod:`.paper` (the paper's numbers),
:mod:`.variants` (policy + reading of the paper's open points), :mod:`.runner` (scenario oracles,
exact reference, one training, process-pool / Ray executors), :mod:`.ros_runner` (the same
trainings through the ROS graph), :mod:`.summary` (statistics and the paper's claims checked),
:mod:`.report` (Markdown), :mod:`.plots` (PNG) and :mod:`.readme` (the README table).
No ROS import except inside :func:`.ros_runner.run_ros`.
"""
