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
