"""flowrun: Flow, the mixed-autonomy traffic RL framework, on libsumo, Gymnasium, SB3 and MCAP."""

__version__ = "0.1.0"
