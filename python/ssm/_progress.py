"""Progress of long calls (a callback or a tqdm bar) and the engine's
warnings as Python warnings."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

from .errors import InputError, SsmWarning, UntrustedAnswerWarning

# the engine words an answer whose error estimate exceeds the accuracy target
# with this phrase (ssm_engine::analyses::untrusted_warning and the forced
# response's curve warnings)
UNTRUSTED = "do not trust"


def warn(messages: Sequence[str], category: type = SsmWarning, depth: int = 1) -> None:
    """Issues each of ``messages`` as a warning of ``category``, pointing at
    the user's call: ``depth`` frames above the caller of ``warn``."""
    for m in messages:
        warnings.warn(m, category, stacklevel=2 + depth)


def warn_engine(messages: Sequence[str], depth: int = 1) -> None:
    """Issues the engine's warnings: an untrusted answer's as
    :class:`UntrustedAnswerWarning`, the others as :class:`SsmWarning`."""
    warn([m for m in messages if UNTRUSTED not in m], SsmWarning, depth + 1)
    warn([m for m in messages if UNTRUSTED in m], UntrustedAnswerWarning, depth + 1)


class Tqdm:
    """A progress callback drawing a ``tqdm`` bar (made at the first call,
    shown after half a second so that short calls draw nothing)."""

    def __init__(self) -> None:
        self._bar: Any = None

    def __call__(self, stage: str, detail: str) -> None:
        if self._bar is None:
            try:  # a widget in a notebook, where ipywidgets is installed
                import ipywidgets  # noqa: F401
                from tqdm.auto import tqdm
            except ImportError:
                from tqdm import tqdm

            self._bar = tqdm(
                total=None,
                bar_format="{desc} [{elapsed}]",
                delay=0.5,
                leave=False,
            )
        # the engine's details name their stage
        self._bar.set_description_str(detail or stage, refresh=False)
        self._bar.update(0)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


class Progress:
    """The progress callback of a call: ``progress`` when it is callable
    (it takes the stage and the detail, two strings, at most ten times a
    second), a ``tqdm`` bar when ``progress`` is true or ``None`` and tqdm is
    installed, nothing otherwise."""

    def __init__(self, progress: Any) -> None:
        self.callback: Any = None
        self._bar: Tqdm | None = None
        if callable(progress):
            self.callback = progress
        elif progress is None or progress is True:
            try:
                import tqdm  # noqa: F401
            except ImportError:
                if progress is True:
                    raise InputError("progress: tqdm is not installed") from None
            else:
                self._bar = Tqdm()
                self.callback = self._bar
        elif progress is not False:
            raise InputError(
                f"progress: give a callable, True, False or None, not {progress!r}"
            )

    def __enter__(self) -> Any:
        return self.callback

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.close()
