"""Build hook for the one compiled module; everything else is in pyproject.toml.

``evomotion.studies.quadruped_plan.rules._walkcore`` (the walking problem's successors in C, the
same results as the Python code it repeats) is optional: without a C compiler the install
goes on and the Python code runs instead (docs/quadruped-plan.md, "Speed").
"""

from setuptools import Extension, setup

setup(ext_modules=[Extension("evomotion.studies.quadruped_plan.rules._walkcore",
                             ["src/evomotion/studies/quadruped_plan/rules/_walkcore.c"],
                             # no FMA contraction, sin and cos called as Python calls them
                             extra_compile_args=["-O2", "-fno-fast-math", "-ffp-contract=off",
                                                 "-fno-builtin-sin", "-fno-builtin-cos"],
                             optional=True)])
