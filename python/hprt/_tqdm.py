"""Progress bars for the long calls: ``progress="tqdm"`` (or ``True``) draws them with a
``TqdmProgress`` of its own, closed when the call ends; make one to choose tqdm's options."""

import importlib
from types import TracebackType
from typing import Any, Optional


class TqdmProgress:
    """A ``progress(stage, done, total)`` callable drawing one tqdm bar per stage (a bake's
    vertices, a reference's rows, each of a composite's two renders). Keyword arguments go to
    each ``tqdm.tqdm`` (``file=``, ``leave=``, ``ncols=``...). tqdm is imported here, when one
    is made: ``ValueError`` if it is not installed. A context manager: leaving it closes the
    bar an interrupted call left open."""

    def __init__(self, **options: Any) -> None:
        try:
            self._tqdm: Any = importlib.import_module("tqdm").tqdm
        except ImportError as error:
            raise ValueError(
                'progress="tqdm" draws bars with tqdm, which is not installed: pip install tqdm'
            ) from error
        self._options = options
        self._bar: Any = None
        self._stage = ""

    def __call__(self, stage: str, done: int, total: int) -> None:
        bar = self._bar
        if bar is None or stage != self._stage or total != bar.total or done < bar.n:
            self.close()
            bar = self._bar = self._tqdm(total=total, desc=stage, **self._options)
            self._stage = stage
        bar.update(done - bar.n)
        if done >= total:
            self.close()

    def close(self) -> None:
        """Closes the open bar, if any."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> "TqdmProgress":
        return self

    def __exit__(
        self,
        kind: Optional[type[BaseException]],
        error: Optional[BaseException],
        traceback: Optional[TracebackType],
    ) -> None:
        self.close()
