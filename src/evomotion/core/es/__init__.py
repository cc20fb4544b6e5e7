"""Evolution strategies for policy search: OpenAI-ES, ARS, PGPE with ClipUp and SNES.

Each optimizer searches with a Gaussian around a *centre* (the distribution mean), which is
what a policy search deploys: :meth:`~evomotion.core.es.common.GaussianES.center`. The
shared pieces are the fitness shaping in :mod:`~evomotion.core.es.ranking` and the
gradient-following steps in :mod:`~evomotion.core.es.adam` and
:mod:`~evomotion.core.es.clipup`; they register in :mod:`evomotion.core.algorithms` as
``openai_es``, ``ars``, ``pgpe`` and ``snes``.
"""
