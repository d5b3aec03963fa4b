"""Pre-flight: everything ``baseline``, ``train`` and ``validate`` check before a run starts.

:mod:`~flowrun.preflight.checks` resolves the environment class and checks its parameters and
network, the numpy backends and, for training, the hyper-parameter names, the policy and the
RLlib options, each at the ``file:line`` of the key to change; :mod:`~flowrun.preflight.prepare`
is ``flowrun train``'s preparation (config or resumed run folder, checks, backend). The layer
sits above :mod:`flowrun.training`, whose modules it imports only when a config trains.
"""
