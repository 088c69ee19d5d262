"""Progress bars with an ETA, in terminals and in Jupyter (tqdm.auto).

Silent when asked to be quiet, and when neither a terminal nor a notebook is
watching (CI logs, pipes), so that logs carry no carriage-return noise. In a
notebook the widget's state is not saved with the notebook, whose static view
(nbviewer, GitHub, the docs) would show the bar as first drawn; so a notebook bar
also prints its final state as one line of text when it closes.
"""

from __future__ import annotations

import sys
import time

#: a bar counts in thousandths of the run
_TOTAL = 1000


def in_notebook() -> bool:
    """True inside a Jupyter kernel (where tqdm.auto draws a widget)."""
    shell = sys.modules.get("IPython")
    if shell is None or "ipykernel" not in sys.modules:
        return False
    try:
        return type(shell.get_ipython()).__name__ == "ZMQInteractiveShell"
    except Exception:  # noqa: BLE001 - an odd IPython is not a notebook
        return False


class ProgressBar:
    """Callable ``bar(fraction, text="")`` with the elapsed time and an ETA.

    Parameters
    ----------
    label : what runs (shown before the bar).
    quiet : never draw.
    stream : where a terminal bar goes (default stderr); drawn only if it is a
        TTY, or in a notebook.
    """

    def __init__(self, label: str, quiet: bool = False, stream=None):
        stream = stream if stream is not None else sys.stderr
        notebook = in_notebook() and stream is sys.stderr
        tty = hasattr(stream, "isatty") and stream.isatty()
        self.enabled = not quiet and (tty or notebook)
        self._bar = None
        self._notebook = notebook
        self._label, self._text, self._start = label, "", time.perf_counter()
        if self.enabled:
            if notebook:
                from tqdm.auto import tqdm
            else:
                from tqdm import tqdm
            self._bar = tqdm(total=_TOTAL, desc=label, file=stream, leave=True,
                             mininterval=0.1, dynamic_ncols=True,
                             bar_format="{desc} {percentage:5.1f}%|{bar}| "
                                        "{elapsed}<{remaining} {postfix}")

    def __call__(self, fraction: float, text: str = "") -> None:
        if self._bar is None:
            return
        n = int(round(_TOTAL * min(max(float(fraction), 0.0), 1.0)))
        if text:
            self._text = text
            self._bar.set_postfix_str(text, refresh=False)
        if n > self._bar.n:
            self._bar.update(n - self._bar.n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.refresh()
            done = 100.0 * self._bar.n / _TOTAL
            self._bar.close()
            self._bar = None
            if self._notebook:
                print(f"{self._label}: {done:.1f} % in {time.perf_counter() - self._start:.3g} s"
                      + (f" ({self._text})" if self._text else ""))
