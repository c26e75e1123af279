"""The ``handbench`` command line (``flags``, ``commands``, ``parser``). Entry point: ``main``."""

from app.cli.parser import main

__all__ = ["main"]
