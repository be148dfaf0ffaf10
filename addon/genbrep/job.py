"""The conversion job: one native `convert` call, run in a worker thread or in the caller's.

No bpy here, and none may be added: the worker thread must never touch Blender data. The
main thread reads `snapshot()` (from a modal timer) and, once the job is over, `result` or
`error`. Cancelling is cooperative: the progress callback returns False at the native
side's next check and the native call raises CancelledError.
"""

import threading
import traceback
from dataclasses import dataclass

PENDING, RUNNING, DONE, FAILED, CANCELLED = "pending", "running", "done", "failed", "cancelled"


@dataclass(frozen=True)
class Snapshot:
    """What the main thread may show about a job at one moment."""
    state: str
    stage: str
    fraction: float


class ConversionJob:
    """Runs `native.convert(design, solids, options, progress)` once.

    native: the genbrep_native module (or anything with convert, ConversionError and
    CancelledError). on_progress(stage, fraction), if given (here or by setting the
    attribute before the job runs), is called from the thread that runs the job, after
    the job's own bookkeeping; it must not touch bpy.
    """

    def __init__(self, native, design, solids, options, on_progress=None):
        self._native = native
        self._args = (design, solids, options)
        self.on_progress = on_progress
        self._lock = threading.Lock()
        self._cancel = threading.Event()
        self._state, self._stage, self._fraction = PENDING, "", 0.0
        self._thread = None
        self.result = None
        self.error = None        # sentence for the user when FAILED
        self.error_code = None   # ConversionError.code, or None
        self.error_stage = None  # ConversionError.stage, or None
        self.details = None      # traceback text of an unexpected exception

    # main thread ------------------------------------------------------------------------

    def start(self):
        """Run in a daemon worker thread; returns at once."""
        self._set_state(RUNNING)
        self._thread = threading.Thread(target=self._run, name="genbrep-convert", daemon=True)
        self._thread.start()

    def run(self):
        """Run in the calling thread; returns the final state."""
        self._set_state(RUNNING)
        self._run()
        return self.state

    def cancel(self):
        """Ask the job to stop at the next progress check. The result, if any, is dropped."""
        self._cancel.set()

    def wait(self, timeout=None):
        """Wait for a started job's thread; True when it has finished."""
        if self._thread is None:
            return self.state not in (PENDING, RUNNING)
        self._thread.join(timeout)
        return not self._thread.is_alive()

    @property
    def state(self):
        with self._lock:
            return self._state

    @property
    def cancel_requested(self):
        return self._cancel.is_set()

    def snapshot(self):
        with self._lock:
            return Snapshot(self._state, self._stage, self._fraction)

    # worker thread ----------------------------------------------------------------------

    def _set_state(self, state):
        with self._lock:
            self._state = state

    def _progress(self, stage, fraction):
        with self._lock:
            self._stage, self._fraction = str(stage), float(fraction)
        if self.on_progress is not None:
            self.on_progress(stage, fraction)
        return not self._cancel.is_set()

    def _run(self):
        native = self._native
        design, solids, options = self._args
        try:
            if self._cancel.is_set():
                raise native.CancelledError("cancelled before the start")
            result = native.convert(design, solids, options, self._progress)
        except native.CancelledError:
            self._set_state(CANCELLED)
        except native.ConversionError as exc:
            self.error = str(exc)
            self.error_code = getattr(exc, "code", None)
            self.error_stage = getattr(exc, "stage", None)
            self._set_state(FAILED)
        except Exception as exc:  # noqa: BLE001 -- never let a worker die silently
            self.error = f"internal error in genbrep_native: {type(exc).__name__}: {exc}"
            self.details = traceback.format_exc()
            self._set_state(FAILED)
        else:
            if self._cancel.is_set():
                self._set_state(CANCELLED)
            else:
                self.result = result
                self._set_state(DONE)
