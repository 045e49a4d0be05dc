"""Arrays that numba does not reference-count, for the exact kernel's hot path.

numba increments and decrements the reference count of every array argument
of every call, even of a function it inlines (an atomic operation through a
call into its runtime each time; docs/performance.md).  A *borrowed* view is
the same array (data, shape, strides) without its memory owner: for it the
reference counting is a no-op that LLVM removes.  The owner must outlive the
view: borrow only arrays that the caller holds (arguments) or that stay
referenced until the view's last use.
"""

from numba.core import cgutils
from numba.extending import intrinsic


@intrinsic
def borrow(typingctx, arr):
    """``arr`` without its memory owner (not reference-counted; see the module)."""

    def impl(context, builder, signature, args):
        src = cgutils.create_struct_proxy(arr)(context, builder, value=args[0])
        dst = cgutils.create_struct_proxy(arr)(context, builder)
        dst.meminfo = cgutils.get_null_value(src.meminfo.type)
        dst.parent = cgutils.get_null_value(src.parent.type)
        dst.nitems = src.nitems
        dst.itemsize = src.itemsize
        dst.data = src.data
        dst.shape = src.shape
        dst.strides = src.strides
        return dst._getvalue()

    return arr(arr), impl
