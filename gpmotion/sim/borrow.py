"""Uncounted views of a tuple's arrays (model, scene, workspace) for the per-step code of a kernel.

numba counts references to an array with an atomic increment and decrement
around every read of it from a tuple (``w.pose``), and its pruning pass
removes few of those pairs in a loop as large as an episode: measured on the
lamp, the atomics took half the step (1.5 µs → 0.75 µs without them).
``borrowed(w)`` gives the same arrays with no owner, so no counting; ``w``
must outlive the views (the episode loop's model, scene and output arrays are
its caller's; its workspace is used once more after the loop, and its state
and scratch are held to the end by ``hold``).  Borrowing the episode's
per-episode views and scratch too made the sine lamp 7 % faster.
"""
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic, overload


def borrowed(w):
    """``w`` itself (Python: nothing is counted); compiled, its arrays without owners."""
    return w


@overload(borrowed, inline="always")
def _borrowed(w):
    return lambda w: _uncounted(w)


@intrinsic
def _uncounted(typingctx, tup):
    """The tuple (or NamedTuple) ``tup`` with each array member without its owner."""
    if not isinstance(tup, types.BaseTuple):
        return None

    def codegen(context, builder, sig, args):
        out = args[0]
        for i, ty in enumerate(tup):
            if not isinstance(ty, types.Array):
                continue
            ary = context.make_array(ty)(context, builder, value=builder.extract_value(out, i))
            ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
            ary.parent = cgutils.get_null_value(ary.parent.type)
            out = builder.insert_value(out, ary._getvalue(), i)
        return out
    return tup(tup), codegen


@njit(cache=True)
def hold(owner):
    """Nothing: a call that keeps ``owner`` (and so its borrowed views) alive up to here."""
