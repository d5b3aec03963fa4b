"""Flow's ``flow.utils``: ``registry.make_create_env`` and ``env_constructor``."""
