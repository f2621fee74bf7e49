"""world/jit_notice.py: one line before the project's kernels compile, none for others."""
import io

import numba
from numba.core import event

from world.jit_notice import CompileNotice


def test_compile_notice_once_and_only_for_the_projects_kernels():
    out = io.StringIO()
    notice = CompileNotice(out)

    def ours(x):
        return x + 1

    def theirs(x):
        return x * 2

    ours.__module__, theirs.__module__ = "raytrace.probe", "elsewhere"
    with event.install_listener("numba:compile", notice):
        assert numba.njit(theirs)(2) == 4           # another package's kernel: silent
        assert out.getvalue() == "" and notice.compiled == 0
        k = numba.njit(ours)
        assert k(1) == 2 and k(2.5) == 3.5          # two signatures: two compiles
        assert k(3) == 4                            # compiled already: no event
    assert notice.compiled == 2
    lines = out.getvalue().splitlines()
    assert len(lines) == 1 and "compiling" in lines[0] and " s;" in lines[0]


def test_importing_the_camera_or_the_ray_kernels_registers_nothing():
    """The notice is installed by whoever runs the work (the CLI, the warm-up), never as a
    side effect of an import."""
    import subprocess
    import sys
    probe = ("import world.camera, raytrace.kernels\n"
             "from numba.core import event\n"
             "from world.jit_notice import CompileNotice\n"
             "print(sum(isinstance(x, CompileNotice) for x in event._registered['numba:compile']))\n"
             "from world import jit_notice\n"
             "jit_notice.install(); jit_notice.install()\n"
             "print(sum(isinstance(x, CompileNotice) for x in event._registered['numba:compile']))\n")
    from conftest import ROOT
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True, cwd=ROOT).stdout.split()
    assert out == ["0", "1"]
