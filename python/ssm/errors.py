"""The exceptions and warnings of ``ssm``.

Every error the engine reports is an :class:`SsmError`; its subclass names the
family (the engine's message is kept as it is). Warnings of the engine (near
resonances, answers whose error estimate exceeds the accuracy target) are
:class:`SsmWarning`, filtered with the standard :mod:`warnings` machinery.
"""


class SsmError(Exception):
    """Any error of the engine."""


class InputError(SsmError, ValueError):
    """An argument the engine cannot take: a shape, dtype, value or index.

    The message starts with the argument's name.
    """


class ModelError(SsmError):
    """The model is inconsistent (a singular mass matrix, a bad constraint)."""


class SpectrumError(SsmError):
    """The spectrum or the master modes could not be computed."""


class ExpansionError(SsmError):
    """The SSM could not be computed (e.g. an inner resonance)."""


class AnalysisError(SsmError):
    """An answer read off the SSM could not be produced."""


class SsmWarning(UserWarning):
    """A warning of the engine (resonances, fallbacks)."""


class UntrustedAnswerWarning(SsmWarning):
    """An answer whose error estimate exceeds the accuracy target."""
