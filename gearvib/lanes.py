"""Eight float64 lanes as one value in numba kernels: explicit SIMD for the batched kernel.

LLVM's loop vectoriser does not vectorise the short loops over the variants of a batch in
numba-compiled code (run-time alias checks between the arrays, trip counts it does not know,
conditional updates), so :mod:`gearvib.kernels_batch` writes its arithmetic on a vector type
of its own: :data:`lanes8`, an LLVM ``<8 x double>`` (one AVX-512 register, two AVX ones, four
SSE2 ones -- LLVM picks the instructions of the host). Values of that type live in registers
across loops, so a sparse product accumulates eight variants at the cost of one.

Every operation is the IEEE operation of each lane (``fadd``, ``fmul``, ... without fast-math
flags, so LLVM neither reassociates nor contracts a multiply and an add into a fused one):
lane ``b`` of a result is bit for bit what the scalar code computes for variant ``b``.
Conditional code is written as selects on lane masks (``where_*``); both branches are
computed, and the selected lane is the branch the scalar code would have taken.

Loads and stores address a C-contiguous float64 array by flat element index (``lanes_load(a,
i)`` reads ``a.flat[i : i + 8]``); they are unchecked, as the callers' buffers are built with
eight lanes on their last axis (:mod:`gearvib.kernels_batch` checks the shapes).
"""

from __future__ import annotations

import operator

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, models, overload, register_model

__all__ = [
    "WIDTH",
    "lanes8",
    "lanes_abs",
    "lanes_any",
    "lanes_bcast",
    "lanes_coef",
    "lanes_floor",
    "lanes_load",
    "lanes_madd",
    "lanes_madd_nz",
    "lanes_madd_nz2",
    "lanes_msub_nz",
    "lanes_scatter",
    "lanes_splat",
    "lanes_store",
    "lanes_table_pair",
    "where_gt",
    "where_le",
    "where_lt",
    "where_ne0",
]

#: Lanes per vector (variants advanced together).
WIDTH = 8
_VEC = ir.VectorType(ir.DoubleType(), WIDTH)
_ZERO = ir.Constant(_VEC, [0.0] * WIDTH)


class Lanes8(types.Type):
    """Numba type of eight float64 lanes (LLVM ``<8 x double>``)."""

    def __init__(self) -> None:
        super().__init__(name="Lanes8")


lanes8 = Lanes8()


@register_model(Lanes8)
class _Lanes8Model(models.PrimitiveModel):
    def __init__(self, dmm, fe_type):
        super().__init__(dmm, fe_type, _VEC)


def _element_ptr(context, builder, arrty, arr, index):
    ary = context.make_array(arrty)(context, builder, arr)
    ptr = builder.gep(ary.data, [index], inbounds=True)
    return builder.bitcast(ptr, _VEC.as_pointer())


def _check_array(arr):
    if not (isinstance(arr, types.Array) and arr.dtype == types.float64
            and arr.layout == "C"):
        raise TypeError("lanes: a C-contiguous float64 array is required")


@intrinsic
def lanes_load(typingctx, arr, index):
    """The eight values ``arr.flat[index : index + 8]``."""
    _check_array(arr)
    if not isinstance(index, types.Integer):
        return None

    def codegen(context, builder, sig, args):
        idx = context.cast(builder, args[1], sig.args[1], types.intp)
        ptr = _element_ptr(context, builder, sig.args[0], args[0], idx)
        return builder.load(ptr, align=8)

    return lanes8(arr, index), codegen


@intrinsic
def lanes_store(typingctx, arr, index, value):
    """Write ``value`` to ``arr.flat[index : index + 8]``."""
    _check_array(arr)
    if not (isinstance(index, types.Integer) and value == lanes8):
        return None

    def codegen(context, builder, sig, args):
        idx = context.cast(builder, args[1], sig.args[1], types.intp)
        ptr = _element_ptr(context, builder, sig.args[0], args[0], idx)
        builder.store(args[2], ptr, align=8)
        return context.get_dummy_value()

    return types.void(arr, index, value), codegen


@intrinsic
def lanes_splat(typingctx, x):
    """``x`` in every lane."""
    if not isinstance(x, (types.Float, types.Integer)):
        return None

    def codegen(context, builder, sig, args):
        v = context.cast(builder, args[0], sig.args[0], types.float64)
        vec = ir.Constant(_VEC, ir.Undefined)
        vec = builder.insert_element(vec, v, ir.Constant(ir.IntType(32), 0))
        return builder.shuffle_vector(vec, vec, ir.Constant(ir.VectorType(ir.IntType(32),
                                                                          WIDTH), [0] * WIDTH))

    return lanes8(x), codegen


def _binary(op):
    @intrinsic
    def impl(typingctx, a, b):
        if not (a == lanes8 and b == lanes8):
            return None

        def codegen(context, builder, sig, args):
            return getattr(builder, op)(args[0], args[1])

        return lanes8(a, b), codegen

    return impl


_add = _binary("fadd")
_sub = _binary("fsub")
_mul = _binary("fmul")
_div = _binary("fdiv")

for _op, _impl in ((operator.add, _add), (operator.sub, _sub), (operator.mul, _mul),
                   (operator.truediv, _div)):
    def _make(impl):
        def ov(a, b):
            if a == lanes8 and b == lanes8:
                return lambda a, b: impl(a, b)
            if a == lanes8 and isinstance(b, (types.Float, types.Integer)):
                return lambda a, b: impl(a, lanes_splat(b))
            if isinstance(a, (types.Float, types.Integer)) and b == lanes8:
                return lambda a, b: impl(lanes_splat(a), b)
            return None
        return ov

    overload(_op, inline="always")(_make(_impl))


@intrinsic
def _neg(typingctx, a):
    if a != lanes8:
        return None

    def codegen(context, builder, sig, args):
        return builder.fneg(args[0])

    return lanes8(a), codegen


@overload(operator.neg, inline="always")
def _ov_neg(a):
    if a == lanes8:
        return lambda a: _neg(a)
    return None


@intrinsic
def where_ne0(typingctx, a, x, y):
    """Per lane ``x if a != 0.0 else y`` (NaN counts as != 0, as Python's ``!=``)."""
    if not all(t == lanes8 for t in (a, x, y)):
        return None

    def codegen(context, builder, sig, args):
        mask = builder.fcmp_unordered("!=", args[0], _ZERO)
        return builder.select(mask, args[1], args[2])

    return lanes8(a, x, y), codegen


def _where(op: str, doc: str):
    """A select on an ordered comparison: per lane ``x if a <op> b else y``."""

    @intrinsic
    def impl(typingctx, a, b, x, y):
        if not all(t == lanes8 for t in (a, b, x, y)):
            return None

        def codegen(context, builder, sig, args):
            mask = builder.fcmp_ordered(op, args[0], args[1])
            return builder.select(mask, args[2], args[3])

        return lanes8(a, b, x, y), codegen

    impl.__doc__ = doc
    return impl


where_gt = _where(">", "Per lane ``x if a > b else y`` (false for NaN, as Python's ``>``).")
where_lt = _where("<", "Per lane ``x if a < b else y`` (false for NaN, as Python's ``<``).")
where_le = _where("<=", "Per lane ``x if a <= b else y`` (false for NaN, as Python's ``<=``).")


def _fused(op: str, nonzero: tuple[int, ...], doc: str):
    """Per lane ``acc <op> a * b`` (a multiply, then ``fadd`` or ``fsub``: no fused
    multiply-add), kept only where every argument of ``nonzero`` (1: ``a``, 2: ``b``) is
    non-zero (NaN counts as non-zero), else ``acc``."""

    @intrinsic
    def impl(typingctx, acc, a, b):
        if not all(t == lanes8 for t in (acc, a, b)):
            return None

        def codegen(context, builder, sig, args):
            out = getattr(builder, op)(args[0], builder.fmul(args[1], args[2]))
            mask = None
            for k in nonzero:
                ne = builder.fcmp_unordered("!=", args[k], _ZERO)
                mask = ne if mask is None else builder.and_(mask, ne)
            return out if mask is None else builder.select(mask, out, args[0])

        return lanes8(acc, a, b), codegen

    impl.__doc__ = doc
    return impl


lanes_madd = _fused("fadd", (), """Per lane ``acc + v * x``. One intrinsic instead of two
overloaded operators: generated code with hundreds of terms compiles faster (numba inlines an
overloaded operator at every use).""")
lanes_madd_nz = _fused("fadd", (1,), """Per lane ``acc + v * x if v != 0 else acc`` (a stored zero
of the batch's common sparsity pattern adds nothing, not even a signed zero).""")
lanes_madd_nz2 = _fused("fadd", (1, 2), "Per lane ``acc + v * x if (v != 0 and x != 0) else acc``.")
lanes_msub_nz = _fused("fsub", (1, 2), "Per lane ``acc - f * v if (f != 0 and v != 0) else acc``.")


def _unary_intrinsic(name):
    @intrinsic
    def impl(typingctx, a):
        if a != lanes8:
            return None

        def codegen(context, builder, sig, args):
            fn = cgutils.get_or_insert_function(
                builder.module, ir.FunctionType(_VEC, [_VEC]), f"llvm.{name}.v{WIDTH}f64")
            return builder.call(fn, [args[0]])

        return lanes8(a), codegen

    return impl


lanes_abs = _unary_intrinsic("fabs")
lanes_abs.__doc__ = "Per lane ``abs(a)``."
lanes_floor = _unary_intrinsic("floor")
lanes_floor.__doc__ = "Per lane ``floor(a)``."


def _gather(builder, data, offsets):
    """The doubles at ``data[offsets[b]]`` of every lane: LLVM's masked gather with every
    lane on (``vgatherqpd`` with AVX-512 or AVX2, scalar loads elsewhere)."""
    i64 = ir.IntType(64)
    vi64 = ir.VectorType(i64, WIDTH)
    base = builder.ptrtoint(data, i64)
    base = builder.insert_element(ir.Constant(vi64, ir.Undefined), base,
                                  ir.Constant(ir.IntType(32), 0))
    base = builder.shuffle_vector(base, base, ir.Constant(ir.VectorType(ir.IntType(32), WIDTH),
                                                          [0] * WIDTH))
    addr = builder.add(base, builder.mul(offsets, ir.Constant(vi64, [8] * WIDTH)))
    pty = ir.VectorType(ir.PointerType(ir.DoubleType()), WIDTH)
    mask_ty = ir.VectorType(ir.IntType(1), WIDTH)
    fn = cgutils.get_or_insert_function(
        builder.module, ir.FunctionType(_VEC, [pty, ir.IntType(32), mask_ty, _VEC]),
        f"llvm.masked.gather.v{WIDTH}f64.v{WIDTH}p0")
    return builder.call(fn, [builder.inttoptr(addr, pty), ir.Constant(ir.IntType(32), 8),
                             ir.Constant(mask_ty, [1] * WIDTH), _ZERO])


def _has_permute(context) -> bool:
    """Whether the target numba compiles for has AVX-512F (a variable lane permute)."""
    features = getattr(context.codegen(), "_tm_features", "") or ""
    return "+avx512f" in features.split(",")


def _permute2(builder, low, high, index):
    """Lane ``b`` of the result is element ``index[b]`` (0 ... 15) of the sixteen lanes of
    ``low`` and ``high`` (``vpermi2pd`` / ``vpermt2pd``, AVX-512F)."""
    vi64 = ir.VectorType(ir.IntType(64), WIDTH)
    fn = cgutils.get_or_insert_function(
        builder.module, ir.FunctionType(_VEC, [_VEC, vi64, _VEC]),
        "llvm.x86.avx512.vpermi2var.pd.512")
    return builder.call(fn, [low, index, high])


@intrinsic
def lanes_table_pair(typingctx, tables, base_left, base_right, n_table, table_width, s):
    """Periodic linear interpolation of two tables at each lane's position ``s`` [cycles].

    ``tables`` is a C-contiguous float64 array whose last axis holds the lanes
    (``table_width == WIDTH``) or one table every lane shares (``table_width == 1``); the
    table of the left flank starts at flat index ``base_left`` (sample ``i`` of lane ``b`` at
    ``base_left + i * WIDTH + b``, shared: ``base_left + i``), the right one at
    ``base_right``; ``n_table`` samples per cycle. Per lane the operations of
    ``gearvib.kernels._interp_cell`` and of the single kernel's
    ``(1 - w) * T[i0] + w * T[i1]``. When every lane is in the same table cell (the
    variants of a sweep mostly are), the samples are two contiguous vector loads per table;
    with a shared table and every lane within 15 samples of the lowest (variants whose
    static deflections differ), with AVX-512, two vector loads of 16 samples per table and a
    permute per sample vector; otherwise two gathers per table. Returns ``(k_left,
    k_right)``.
    """
    _check_array(tables)
    if not (all(isinstance(t, types.Integer) for t in (base_left, base_right, n_table,
                                                       table_width)) and s == lanes8):
        return None

    def codegen(context, builder, sig, args):
        arr, b_l, b_r, nt, tw, s_ = args
        i64 = ir.IntType(64)
        i32 = ir.IntType(32)
        vi64 = ir.VectorType(i64, WIDTH)
        data = context.make_array(sig.args[0])(context, builder, arr).data
        b_l = context.cast(builder, b_l, sig.args[1], types.int64)
        b_r = context.cast(builder, b_r, sig.args[2], types.int64)
        nt = context.cast(builder, nt, sig.args[3], types.int64)
        tw = context.cast(builder, tw, sig.args[4], types.int64)
        per_lane = builder.icmp_signed("==", tw, ir.Constant(i64, WIDTH))

        def splat(x, vty):
            vec = builder.insert_element(ir.Constant(vty, ir.Undefined), x,
                                         ir.Constant(i32, 0))
            return builder.shuffle_vector(vec, vec, ir.Constant(ir.VectorType(i32, WIDTH),
                                                                [0] * WIDTH))

        floor = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(_VEC, [_VEC]), f"llvm.floor.v{WIDTH}f64")
        frac = builder.fsub(s_, builder.call(floor, [s_]))
        u = builder.fmul(frac, splat(builder.sitofp(nt, ir.DoubleType()), _VEC))
        i0 = builder.fptosi(u, vi64)
        w = builder.fsub(u, builder.sitofp(i0, _VEC))
        ntv = splat(nt, vi64)
        zi = ir.Constant(vi64, [0] * WIDTH)
        wrap = builder.icmp_signed(">=", i0, ntv)
        i0 = builder.select(wrap, zi, i0)
        w = builder.select(wrap, _ZERO, w)
        i1 = builder.add(i0, ir.Constant(vi64, [1] * WIDTH))
        i1 = builder.select(builder.icmp_signed("==", i1, ntv), zi, i1)
        first = builder.extract_element(i0, ir.Constant(i32, 0))
        same = builder.icmp_signed("==", i0, splat(first, vi64))
        all_same = builder.icmp_unsigned(
            "==", builder.bitcast(same, ir.IntType(WIDTH)), ir.Constant(ir.IntType(WIDTH), -1))
        slots = [cgutils.alloca_once(builder, _VEC) for _ in range(4)]
        lane_step = builder.zext(per_lane, i64)
        with builder.if_else(all_same, likely=True) as (then, otherwise):
            with then:
                first1 = builder.extract_element(i1, ir.Constant(i32, 0))
                for slot, base, idx in zip(slots, (b_l, b_l, b_r, b_r),
                                           (first, first1, first, first1), strict=True):
                    ptr = builder.gep(data, [builder.add(base, builder.mul(idx, tw))],
                                      inbounds=True)
                    with builder.if_else(per_lane) as (vector, shared):
                        with vector:
                            vptr = builder.bitcast(ptr, _VEC.as_pointer())
                            builder.store(builder.load(vptr, align=8), slot)
                        with shared:
                            builder.store(splat(builder.load(ptr), _VEC), slot)
            with otherwise:  # lanes in different cells
                def gathers():  # one gather per sample vector
                    lanes_off = builder.mul(splat(lane_step, vi64),
                                            ir.Constant(vi64, list(range(WIDTH))))
                    twv = splat(tw, vi64)
                    for slot, base, iv in zip(slots, (b_l, b_l, b_r, b_r), (i0, i1, i0, i1),
                                              strict=True):
                        off = builder.add(builder.add(splat(base, vi64),
                                                      builder.mul(iv, twv)), lanes_off)
                        builder.store(_gather(builder, data, off), slot)

                if not _has_permute(context):
                    gathers()
                else:
                    # a shared table and the cells within fifteen samples: two loads of the
                    # sixteen samples from the lowest cell per table, each lane's two
                    # samples picked by a permute (instead of two gathers)
                    reduce = {op: cgutils.get_or_insert_function(
                        builder.module, ir.FunctionType(i64, [vi64]),
                        f"llvm.vector.reduce.{op}.v{WIDTH}i64") for op in ("smin", "smax")}
                    lo = builder.call(reduce["smin"], [i0])
                    hi = builder.call(reduce["smax"], [i0])
                    fits = builder.and_(
                        builder.not_(per_lane),
                        builder.and_(
                            builder.icmp_signed("<=", builder.sub(hi, lo),
                                                ir.Constant(i64, 2 * WIDTH - 2)),
                            builder.icmp_signed("<", builder.add(lo, ir.Constant(
                                i64, 2 * WIDTH - 1)), nt)))
                    with builder.if_else(fits, likely=True) as (window, scattered):
                        with window:
                            rel0 = builder.sub(i0, splat(lo, vi64))
                            rel1 = builder.add(rel0, ir.Constant(vi64, [1] * WIDTH))
                            for (s0, s1), base in zip((slots[:2], slots[2:]), (b_l, b_r),
                                                      strict=True):
                                ptr = builder.gep(data, [builder.add(base, lo)],
                                                  inbounds=True)
                                win0 = builder.load(builder.bitcast(ptr, _VEC.as_pointer()),
                                                    align=8)
                                ptr = builder.gep(ptr, [ir.Constant(i64, WIDTH)],
                                                  inbounds=True)
                                win1 = builder.load(builder.bitcast(ptr, _VEC.as_pointer()),
                                                    align=8)
                                builder.store(_permute2(builder, win0, win1, rel0), s0)
                                builder.store(_permute2(builder, win0, win1, rel1), s1)
                        with scattered:
                            gathers()
        t_l0, t_l1, t_r0, t_r1 = (builder.load(slot) for slot in slots)
        omw = builder.fsub(ir.Constant(_VEC, [1.0] * WIDTH), w)
        kl = builder.fadd(builder.fmul(omw, t_l0), builder.fmul(w, t_l1))
        kr = builder.fadd(builder.fmul(omw, t_r0), builder.fmul(w, t_r1))
        return context.make_tuple(builder, sig.return_type, (kl, kr))

    return (types.UniTuple(lanes8, 2)(tables, base_left, base_right, n_table, table_width, s),
            codegen)


@intrinsic
def lanes_bcast(typingctx, arr, index):
    """``arr.flat[index]`` in every lane."""
    _check_array(arr)
    if not isinstance(index, types.Integer):
        return None

    def codegen(context, builder, sig, args):
        idx = context.cast(builder, args[1], sig.args[1], types.intp)
        ary = context.make_array(sig.args[0])(context, builder, args[0])
        x = builder.load(builder.gep(ary.data, [idx], inbounds=True))
        vec = builder.insert_element(ir.Constant(_VEC, ir.Undefined), x,
                                     ir.Constant(ir.IntType(32), 0))
        return builder.shuffle_vector(
            vec, vec, ir.Constant(ir.VectorType(ir.IntType(32), WIDTH), [0] * WIDTH))

    return lanes8(arr, index), codegen


@intrinsic
def lanes_coef(typingctx, arr, index, uniform):
    """``arr.flat[index : index + 8]``, or when ``uniform`` is non-zero (every lane holds the
    same value there) ``arr.flat[index]`` in every lane: one scalar load broadcast instead of
    a vector load (the loads are what bounds the batched sparse products)."""
    _check_array(arr)
    if not (isinstance(index, types.Integer) and isinstance(uniform, (types.Integer,
                                                                      types.Boolean))):
        return None

    def codegen(context, builder, sig, args):
        idx = context.cast(builder, args[1], sig.args[1], types.intp)
        ary = context.make_array(sig.args[0])(context, builder, args[0])
        ptr = builder.gep(ary.data, [idx], inbounds=True)
        flag = context.cast(builder, args[2], sig.args[2], types.boolean)
        slot = cgutils.alloca_once(builder, _VEC)
        with builder.if_else(flag) as (shared, per_lane):
            with shared:
                x = builder.load(ptr)
                vec = builder.insert_element(ir.Constant(_VEC, ir.Undefined), x,
                                             ir.Constant(ir.IntType(32), 0))
                builder.store(builder.shuffle_vector(
                    vec, vec, ir.Constant(ir.VectorType(ir.IntType(32), WIDTH), [0] * WIDTH)),
                    slot)
            with per_lane:
                builder.store(builder.load(builder.bitcast(ptr, _VEC.as_pointer()), align=8),
                              slot)
        return builder.load(slot)

    return lanes8(arr, index, uniform), codegen


@intrinsic
def lanes_scatter(typingctx, arr, index, stride, value):
    """Write lane ``b`` of ``value`` to ``arr.flat[index + b * stride]`` (a transposing
    store: one lane into each of eight rows)."""
    _check_array(arr)
    if not (isinstance(index, types.Integer) and isinstance(stride, types.Integer)
            and value == lanes8):
        return None

    def codegen(context, builder, sig, args):
        idx = context.cast(builder, args[1], sig.args[1], types.intp)
        step = context.cast(builder, args[2], sig.args[2], types.intp)
        data = context.make_array(sig.args[0])(context, builder, args[0]).data
        for b in range(WIDTH):
            x = builder.extract_element(args[3], ir.Constant(ir.IntType(32), b))
            off = builder.add(idx, builder.mul(step, ir.Constant(idx.type, b)))
            builder.store(x, builder.gep(data, [off], inbounds=True))
        return context.get_dummy_value()

    return types.void(arr, index, stride, value), codegen


@intrinsic
def lanes_any(typingctx, a):
    """Whether any lane of ``a`` is non-zero (NaN counts as non-zero)."""
    if a != lanes8:
        return None

    def codegen(context, builder, sig, args):
        mask = builder.fcmp_unordered("!=", args[0], _ZERO)
        bits = builder.bitcast(mask, ir.IntType(WIDTH))
        return builder.icmp_unsigned("!=", bits, ir.Constant(ir.IntType(WIDTH), 0))

    return types.boolean(a), codegen
