"""Arrays that numba does not reference-count, for the exact kernel's hot path.

numba increments and decrements the reference count of every array argument
of every call, even of a function it inlines (an atomic operation through a
call into its runtime each time; docs/performance.md).  A *borrowed* view is
the same array (data, shape, strides) without its memory owner: for it the
reference counting is a no-op that LLVM removes.  The owner must outlive the
view: borrow only arrays that the caller holds (arguments) or that stay
referenced until the view's last use.
"""

from numba.core import cgutils, types
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


@intrinsic
def with_len(typingctx, arr, n):
    """The 1-d array ``arr`` seen with length ``n`` (at most its own; not checked) and
    without its memory owner: where ``n`` is a constant, loops over ``arr.shape[0]``
    unroll (the kernel's specialisations by mode count)."""
    if not (isinstance(arr, types.Array) and arr.ndim == 1 and isinstance(n, types.Integer)):
        return None

    def impl(context, builder, signature, args):
        src = cgutils.create_struct_proxy(arr)(context, builder, value=args[0])
        dst = cgutils.create_struct_proxy(arr)(context, builder)
        ln = context.cast(builder, args[1], n, types.intp)
        dst.meminfo = cgutils.get_null_value(src.meminfo.type)
        dst.parent = cgutils.get_null_value(src.parent.type)
        dst.nitems = ln
        dst.itemsize = src.itemsize
        dst.data = src.data
        dst.shape = cgutils.pack_array(builder, [ln])
        dst.strides = src.strides
        return dst._getvalue()

    return arr(arr, n), impl
