"""The sweep's Dask worker plugin: each worker makes its GL context once, when it joins,
in the thread that runs its cells, and releases it (with its Renderers and the sweep's
copies of the scenes on its machine) when the plugin is removed at the sweep's end or the
worker closes. Registered through the client, so the scheduler gives it to every worker,
those of a cluster started by hand and those that join later (a restarted one) included.
"""
from __future__ import annotations

import asyncio
import signal
import threading

from distributed import WorkerPlugin

from .bundle import remove_copies
from .cells import close_gl, open_gl


def _device() -> str:
    from ..glcontext import device_name
    return device_name(open_gl())


class SweepWorker(WorkerPlugin):
    """`quiet_interrupt`: a worker of the sweep's own LocalCluster ignores SIGINT (a
    terminal's Ctrl-C reaches the whole process group; the sweep closes its workers)."""

    def __init__(self, run: str, quiet_interrupt: bool = False):
        self.run = run
        self.name = f"hmblur-sweep-{run}"      # one per sweep: two sweeps on a cluster
        self.quiet_interrupt = quiet_interrupt
        self.device = None

    async def _in_cell_thread(self, worker, fn):
        # The default executor is the thread pool cells run in (one thread: --nthreads 1).
        return await asyncio.get_running_loop().run_in_executor(
            worker.executors["default"], fn)

    async def setup(self, worker):
        if self.quiet_interrupt and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        # A worker without EGL fails here, once, and the sweep says so before any cell.
        self.device = await self._in_cell_thread(worker, _device)

    async def teardown(self, worker):
        try:
            await self._in_cell_thread(worker, close_gl)
        finally:
            remove_copies(self.run)
