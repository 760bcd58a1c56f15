"""MotionBenchMaker (MBM) on the Franka Panda: the problems, their conversion to dynfab
scenarios, and the benchmark that runs them (``dynfab benchmark mbm``).

MBM: C. Chamzas, C. Quintero-Peña, Z. Kingston, A. Orthey, D. Rakita, M. Gleicher,
M. Toussaint, L. E. Kavraki, "MotionBenchMaker: A Tool to Generate and Benchmark Motion
Planning Datasets", IEEE Robotics and Automation Letters 7(2), 2022. The problem sets are
those KavrakiLab/vamp ships (Apache-2.0, ``data/LICENSE-vamp``; MBM itself is BSD-3-Clause,
``data/LICENSE-motion_bench_maker``); ``data/README.md`` says what the bundled files are.
New problems of the same types are drawn from MBM's bundled configs
(:mod:`dynfab.benchmarks.mbm.generated_problems`, ``--source generated``).
"""
