"""Named exceptions for errors a user can cause. Each message lists the valid choices."""

from __future__ import annotations


class HandbenchError(Exception):
    """Base class of every error a user can cause; the CLI prints these without a traceback."""


class DesignError(HandbenchError, ValueError):
    """A thumb design (CMC/MCP angle) that is not a finite value inside the design range."""


class UnknownObjectError(HandbenchError, KeyError):
    """An object key that is not one of the shipped or imported objects."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class MeshImportError(HandbenchError, ValueError):
    """A user mesh that cannot be turned into a usable object (empty, NaN, absurd size...)."""


class SettingsError(HandbenchError, ValueError):
    """A simulation setting outside its valid range or choices."""


class StoreError(HandbenchError):
    """A results database that is corrupt, foreign, or from an incompatible version."""


class UnknownHypothesisError(HandbenchError, KeyError):
    """A grasp-hypothesis id or index that does not exist for the chosen object."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class TableError(HandbenchError, ValueError):
    """A score table (ours or a reference) that cannot be read or lacks needed columns."""


class WorkerCrashError(HandbenchError):
    """A worker process died (segfault, out of memory, killed) while simulating; the message
    names the object and the hypothesis it was on. Finished tasks stay in the store."""
