"""pik_gen: the .pik kernel compiler behind the `pikg-gen` command."""

__version__ = "0.1.0"
