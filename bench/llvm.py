"""Points Dr.Jit (Mitsuba 3's LLVM backend) at an LLVM it can use.

Dr.Jit needs LLVM 19 or newer (15 aborts on fminimum); a machine may have an older one installed
beside it (Debian's libllvm14, say), which Dr.Jit could pick up and then
abort on. `use_newest_llvm()` sets DRJIT_LIBLLVM_PATH to the newest LLVM
shared library of version 19 or newer (Debian's libllvmN installs
/usr/lib/<triplet>/libLLVM-N.so; llvm-N-dev /usr/lib/llvm-N/lib/libLLVM.so),
unless the variable is set already. Call it before importing drjit or mitsuba.
"""

import glob
import os
import re


def use_newest_llvm():
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return os.environ["DRJIT_LIBLLVM_PATH"]
    found = []
    for path in glob.glob("/usr/lib/*-linux-gnu/libLLVM-*.so") + glob.glob("/usr/lib/llvm-*/lib/libLLVM-*.so"):
        m = re.search(r"libLLVM-(\d+)\.so$", path)
        if m and int(m.group(1)) >= 19:
            found.append((int(m.group(1)), path))
    if found:
        os.environ["DRJIT_LIBLLVM_PATH"] = max(found)[1]
    return os.environ.get("DRJIT_LIBLLVM_PATH")
