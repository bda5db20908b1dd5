"""A software prefetch for the weigh stage's compiled loops (numba): the loops read each
hit's face rows (normal, plane offset, weight cache) at random, and on meshes whose face
arrays outgrow the last-level cache every new face is a trip to memory. Asking for the rows
of the hit :data:`AHEAD` places later lets those trips overlap the work on the hits between.

Measured on a 2-core AVX-512 EPYC (32 MiB L3), rays to bins of 1e6-ray views of
icospheres, flat normals, SR, one thread: 1.31M faces 6.5 % faster, 5.2M 7.7 %, 328k
faces unchanged, 82k 1.2 % slower (there every row is in cache and the prefetches are pure
cost): the loops prefetch from :data:`PREFETCH_FROM` faces on. A prefetch changes no
number: the same bits either way.
"""

from __future__ import annotations

from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

from ._compiled import njit_loop

__all__ = ["prefetch", "ahead", "AHEAD", "AHEAD_SINGLE", "PREFETCH_FROM"]

#: How many hits ahead the loops prefetch (24 to 64 measured alike at 1.31M faces).
AHEAD = 32
#: The same for hits of rays cast one at a time: a sparse grid's few hits a band, each
#: after a whole cast (2,000 views of 1,444 rays of an 82k sphere, stratified, one
#: thread, in alternate runs: 0.79-0.80x raw embreex at 8 or 32, 0.80-0.82x at 16).
AHEAD_SINGLE = 16
#: Meshes of this many faces or more prefetch (their per-face arrays, ~52 bytes a face,
#: exceed a 16–32 MiB last-level cache).
PREFETCH_FROM = 1 << 19
#: A distance beyond any view's hits: no prefetch.
_NEVER = 1 << 62


@njit_loop(inline="always")
def ahead(face_normals, single=False):                    # pragma: no cover - compiled
    """How many hits ahead a loop over the hits on this mesh (``face_normals``, one row a
    face) prefetches their faces' rows: :data:`AHEAD` from :data:`PREFETCH_FROM` faces on,
    or :data:`AHEAD_SINGLE` at any size where the rays were cast one at a time
    (``single``: a sparse grid, whose every hit is a new face and whose casts, between two
    hits, evict the rows: 82k faces, 2,000 views of 1,444 rays, flat, one thread: 4 %
    faster); else a distance past every hit (none). The loops write the test out themselves
    (``if i + ahead < n and prim[i + ahead] >= 0: prefetch((a, b), prim[i + ahead])``):
    a helper function holding it, even inlined, made them slower."""
    if single:
        return AHEAD_SINGLE
    return AHEAD if face_normals.shape[0] >= PREFETCH_FROM else _NEVER


@intrinsic
def prefetch(typingctx, arrays, index):                   # pragma: no cover - compiled
    """Prefetch the cache line of ``a[index, 0, ...]`` for reading, for ``arrays`` one
    array a or a tuple of them (an integer ``index`` into the first axis, not checked: the
    callers pass face indices of hits), into every cache level (LLVM's ``llvm.prefetch``,
    locality 3); no effect on any value."""
    group = arrays if isinstance(arrays, types.BaseTuple) else (arrays,)
    if not all(isinstance(a, types.Array) for a in group) or \
            not isinstance(index, types.Integer):
        return None
    sig = types.void(arrays, index)

    def codegen(context, builder, signature, args):
        at = context.cast(builder, args[1], signature.args[1], types.intp)
        if isinstance(signature.args[0], types.BaseTuple):
            for k, aryty in enumerate(signature.args[0]):
                _fetch_row(context, builder, aryty, builder.extract_value(args[0], k), at)
        else:
            _fetch_row(context, builder, signature.args[0], args[0], at)
        return context.get_dummy_value()

    return sig, codegen


def _fetch_row(context, builder, aryty, value, at):
    """Emit the prefetch of row ``at`` of one array (``value`` of numba type ``aryty``)."""
    ary = context.make_array(aryty)(context, builder, value)
    zero = context.get_constant(types.intp, 0)
    ptr = cgutils.get_item_pointer(context, builder, aryty, ary,
                                   [at] + [zero] * (aryty.ndim - 1), wraparound=False)
    i8p = ir.IntType(8).as_pointer()
    i32 = ir.IntType(32)
    fnty = ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32])
    # named by llvmlite for its pointer type (p0i8; LLVM 15 on renames it p0 itself)
    fn = builder.module.declare_intrinsic("llvm.prefetch", [i8p], fnty)
    builder.call(fn, [builder.bitcast(ptr, i8p), ir.Constant(i32, 0), ir.Constant(i32, 3),
                      ir.Constant(i32, 1)])
