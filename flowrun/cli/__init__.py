"""The ``flowrun`` command line (the only layer that prints)."""
