"""Forward-mode derivatives of the kernels, by source transformation of the same scalar source (issue 31).

:func:`forward_twin` reads a jitted scalar function's Python source (``inspect.getsource``), and
writes a new function in which every float local ``x`` that depends on a differentiated input
carries its tangents ``x__d0 … x__d{N−1}`` beside it — one per differentiated parameter, all in ONE
pass (a vector of tangents, each a plain scalar local, so numba keeps them in registers and LLVM
vectorises the driver's loop across pairs as it does for ``eval``). No formula is copied: the
primal lines are the source's own, and each tangent line is the derivative rule of the operation
that line performs:

* ``a ± b``, ``a · b``, ``a / b``, ``a ** b``, unary minus;
* ``math.sqrt exp log log1p expm1 pow sin cos tan asin acos atan atan2 sinh cosh tanh erf erfc hypot
  fabs copysign`` (``fabs``/``abs``: the sign of the argument, +1 at 0); ``floor ceil trunc`` and
  ``int()``: derivative 0;
* ``min``/``max`` (and so every clamp written with them) and ``a if cond else b``: **the derivative
  of the branch the code takes** — ``min(a, b)`` returns ``b`` only where ``b < a`` (Python's rule),
  so at a tie the derivative is ``a``'s. ``if``/``else`` statements likewise differentiate the branch
  taken. This is the one-sided derivative at a kink, documented in ``docs/api.md``;
* calls of other jitted functions: their own forward twin, specialised to which arguments carry
  tangents and which tangent components can be nonzero (a static sparsity pattern, computed by a
  fixpoint over the function's assignments: ``ks_r``'s tangent is never formed in the green channel).

The kernel's parameter array ``p`` is the seed: ``p[k]`` with a constant ``k`` in the seed set (all of
``0 … N−1``, or the components asked for, ``eval_grad(wrt=…)``) has the unit tangent ``e_k``; every other
subscript (another parameter, a table in ``p``) is a constant, so a twin seeded by fewer parameters
carries fewer tangents and does less work. The generated sources are
written to ``<cache_dir>/forward/`` and imported from there with ``cache=True``, so numba's disk
cache holds their machine code (a new process does not recompile). Beside a kernel's twin, a
manifest (``<stem>.json``: the twins it calls, in load order, and their return patterns) lets a new
process load them without reading and analysing the sources again (:func:`forward_kernel`; for the
package's own kernels only, whose source the cache folder's name is a hash of).
"""

from __future__ import annotations

import ast
import inspect
import textwrap
import threading
from typing import Callable

from .cache import load_generated
from .reference import _is_jitted

_LOCK = threading.RLock()
#: (id of source function, arg patterns, N) -> (dispatcher, return patterns)
_TWINS: dict[tuple, tuple[Callable, tuple]] = {}

Pattern = frozenset  # the tangent components that may be nonzero
EMPTY: frozenset = frozenset()
P_ARRAY = "P"  # marker: this argument is the kernel's parameter array (the seed)


class Unsupported(Exception):
    """A construct the transformation does not handle (the model then has no gradient)."""


def _name(s: str) -> ast.Name:
    return ast.Name(id=s, ctx=ast.Load())


def _num(v: float) -> ast.Constant:
    return ast.Constant(value=v)


def _expr(src: str) -> ast.expr:
    return ast.parse(src, mode="eval").body


_MATH_UNARY = {
    # name: derivative as a source template in x (the argument) and r (the result), which the tangent
    # multiplies (log and log1p: _QUOTIENT_RULES). Where the derivative is infinite (acos at ±1) the rule
    # gives the IEEE infinity instead of dividing by zero, which raises in Python (the reference engine)
    # and gives inf in numba: both engines then compute the same tangent; a zero tangent that meets it
    # stays 0 (_UNBOUNDED_RULES), and an infinite tangent that only feeds floor/int/a comparison is
    # dropped, as in htsg_series.thinning_step.
    "sqrt": "(0.5 / r if r > 0.0 else 0.0)",
    "exp": "r",
    "expm1": "(r + 1.0)",
    "sin": "math.cos(x)",
    "cos": "(-math.sin(x))",
    "tan": "(1.0 + r * r)",
    "asin": "(1.0 / math.sqrt(1.0 - x * x) if x * x < 1.0 else math.inf)",
    "acos": "(-1.0 / math.sqrt(1.0 - x * x) if x * x < 1.0 else -math.inf)",
    "atan": "(1.0 / (1.0 + x * x))",
    "sinh": "math.cosh(x)",
    "cosh": "math.sinh(x)",
    "tanh": "(1.0 - r * r)",
    "erf": "(1.1283791670955126 * math.exp(-x * x))",
    "erfc": "(-1.1283791670955126 * math.exp(-x * x))",
    "fabs": "(1.0 if x >= 0.0 else -1.0)",
    "floor": None,
    "ceil": None,
    "trunc": None,
}
#: name: the source template in x of the expression whose reciprocal is the derivative. The twin divides the
#: tangent by it instead of multiplying by its reciprocal, which overflows first (ln d of a subnormal d:
#: 1/d = inf where ∂d/d is ~1e300, Lafortune's lobe d^n = exp(n ln d) with C_z = 1e-300 at a grazing
#: pair); where it is 0 the derivative is ±inf, and a zero tangent stays 0 (Lafortune's ∂/∂C_y where
#: u_y v_y = 0 at a subnormal d: not 0 · inf)
_QUOTIENT_RULES = {"log": "x", "log1p": "(1.0 + x)"}
#: the rules of _MATH_UNARY that are infinite somewhere or overflow near it (0.5/√x of a subnormal x, asin
#: and acos at ±1): their twin multiplies only a nonzero tangent by them, a zero one stays 0
_UNBOUNDED_RULES = frozenset({"sqrt", "asin", "acos"})


class _Func:
    """The transformation of one source function for one pattern of its arguments."""

    def __init__(self, fn: Callable, arg_patterns: tuple, seeds: frozenset, direction: int | None = None):
        self.fn = fn
        self.py = getattr(fn, "py_func", fn)
        self.seeds = seeds
        self.direction = direction  # None: a tangent per seed; else one tangent, p[k]'s being p[direction + k]
        src = textwrap.dedent(inspect.getsource(self.py))
        tree = ast.parse(src)
        self.fdef = tree.body[0]
        if not isinstance(self.fdef, ast.FunctionDef):
            raise Unsupported(f"{self.py.__qualname__}: not a function definition")
        self.args = [a.arg for a in self.fdef.args.args]
        if len(arg_patterns) != len(self.args):
            raise Unsupported(f"{self.py.__qualname__}: {len(arg_patterns)} argument patterns for {len(self.args)}")
        self.arg_patterns = dict(zip(self.args, arg_patterns))
        self.g = self.py.__globals__
        self.assigned = {t.id for node in ast.walk(self.fdef) for t in _targets(node)}
        self.ntmp = 0
        self.callees: dict[str, tuple[Callable, tuple]] = {}  # generated name -> (twin, return patterns)
        self.callee_src: dict[str, tuple[Callable, tuple]] = {}

    # ------------------------------------------------------------------ patterns (a fixpoint)
    def analyse(self) -> None:
        self.pat: dict[str, frozenset] = {a: (p if isinstance(p, frozenset) else EMPTY)
                                          for a, p in self.arg_patterns.items()}
        self.ret: list[frozenset] | None = None
        for _ in range(50):
            before = (dict(self.pat), None if self.ret is None else list(self.ret))
            self._walk(self.fdef.body)
            if (dict(self.pat), None if self.ret is None else list(self.ret)) == before:
                return
        raise Unsupported(f"{self.py.__qualname__}: tangent patterns do not settle")

    def _walk(self, body) -> None:
        for st in body:
            if isinstance(st, ast.Assign):
                if len(st.targets) != 1:
                    raise Unsupported("chained assignment")
                self._assign_pat(st.targets[0], st.value)
            elif isinstance(st, ast.AugAssign):
                tgt = st.target
                if not isinstance(tgt, ast.Name):
                    raise Unsupported("augmented assignment to a non-name")
                self._join(tgt.id, self.pat.get(tgt.id, EMPTY) | self.epat(st.value))
            elif isinstance(st, ast.If):
                self._walk(st.body)
                self._walk(st.orelse)
            elif isinstance(st, (ast.For, ast.While)):
                if isinstance(st, ast.For) and not isinstance(st.target, ast.Name):
                    raise Unsupported("for over a tuple target")
                self._walk(st.body)
                self._walk(st.orelse)
            elif isinstance(st, ast.Return):
                pats = self._ret_pats(st.value)
                if self.ret is None:
                    self.ret = pats
                else:
                    if len(pats) != len(self.ret):
                        raise Unsupported("returns of different arity")
                    self.ret = [a | b for a, b in zip(self.ret, pats)]
            elif isinstance(st, (ast.Expr, ast.Pass, ast.Break, ast.Continue)):
                pass
            else:
                raise Unsupported(f"statement {type(st).__name__}")

    def _join(self, name: str, p: frozenset) -> None:
        self.pat[name] = self.pat.get(name, EMPTY) | p

    def _assign_pat(self, target, value) -> None:
        if isinstance(target, ast.Name):
            self._join(target.id, self.epat(value))
        elif isinstance(target, ast.Tuple):
            pats = self._tuple_pats(value, len(target.elts))
            for t, p in zip(target.elts, pats):
                if not isinstance(t, ast.Name):
                    raise Unsupported("nested assignment target")
                self._join(t.id, p)
        else:
            raise Unsupported(f"assignment to {type(target).__name__}")

    def _ret_pats(self, value) -> list:
        if value is None:
            return [EMPTY]
        if isinstance(value, ast.Tuple):
            return [self.epat(e) for e in value.elts]
        if isinstance(value, ast.Call) and self._callee(value) is not None:
            return list(self._call_pats(value))
        return [self.epat(value)]

    def _tuple_pats(self, value, k: int) -> list:
        if isinstance(value, ast.Tuple):
            return [self.epat(e) for e in value.elts]
        if isinstance(value, ast.Call) and self._callee(value) is not None:
            pats = list(self._call_pats(value))
            if len(pats) != k:
                raise Unsupported("tuple unpacking of a different arity")
            return pats
        raise Unsupported("tuple assignment from an expression")

    def _callee(self, call: ast.Call):
        f = call.func
        if isinstance(f, ast.Name):
            obj = self.g.get(f.id)
            if obj is not None and _is_jitted(obj):
                return obj
        return None

    def _arg_pat(self, a) -> object:
        if isinstance(a, ast.Name) and self.arg_patterns.get(a.id) == P_ARRAY and a.id in self.args:
            return P_ARRAY
        k = self.static_int(a)
        if k is not None:  # an integer known here (an offset into p): the callee is specialised to it
            return ("int", k)
        return self.epat(a)

    def static_int(self, e):
        """The value of an integer expression known when the function is transformed, else None."""
        if isinstance(e, ast.Constant) and type(e.value) is int:
            return e.value
        if isinstance(e, ast.Name):
            p = self.arg_patterns.get(e.id)
            if isinstance(p, tuple) and p[0] == "int" and e.id not in self.assigned:
                return p[1]
            return None
        if isinstance(e, ast.BinOp) and isinstance(e.op, (ast.Add, ast.Sub, ast.Mult)):
            a, b = self.static_int(e.left), self.static_int(e.right)
            if a is None or b is None:
                return None
            return a + b if isinstance(e.op, ast.Add) else (a - b if isinstance(e.op, ast.Sub) else a * b)
        return None

    def _call_pats(self, call: ast.Call) -> tuple:
        obj = self._callee(call)
        pats = tuple(self._arg_pat(a) for a in call.args)
        _, rets = forward_function(obj, pats, self.seeds, self.direction)
        return rets

    def epat(self, e) -> frozenset:
        """The tangent components of expression ``e`` that may be nonzero."""
        if isinstance(e, ast.Constant):
            return EMPTY
        if isinstance(e, ast.Name):
            p = self.pat.get(e.id, EMPTY)
            return p if isinstance(p, frozenset) else EMPTY
        if isinstance(e, ast.BinOp):
            if isinstance(e.op, (ast.FloorDiv, ast.BitAnd, ast.BitOr, ast.BitXor, ast.LShift, ast.RShift)):
                return EMPTY
            return self.epat(e.left) | self.epat(e.right)
        if isinstance(e, ast.UnaryOp):
            return EMPTY if isinstance(e.op, ast.Not) else self.epat(e.operand)
        if isinstance(e, (ast.Compare, ast.BoolOp)):
            return EMPTY
        if isinstance(e, ast.IfExp):
            return self.epat(e.body) | self.epat(e.orelse)
        if isinstance(e, ast.Subscript):
            v = e.value
            k = self.static_int(e.slice)
            if isinstance(v, ast.Name) and self.arg_patterns.get(v.id) == P_ARRAY and k is not None and k in self.seeds:
                return frozenset([0 if self.direction is not None else k])
            return EMPTY  # a table in p, or another array: a constant
        if isinstance(e, ast.Attribute):
            return EMPTY
        if isinstance(e, ast.Call):
            if self._callee(e) is not None:
                rets = self._call_pats(e)
                if len(rets) != 1:
                    raise Unsupported("a tuple-valued call inside an expression")
                return rets[0]
            fname = _call_name(e)
            if fname in ("int", "len", "range", "bool"):
                return EMPTY
            out = EMPTY
            for a in (e.args[1:] if fname == "select" else e.args):
                out |= self.epat(a)
            if fname in ("floor", "ceil", "trunc"):
                return EMPTY
            return out
        raise Unsupported(f"expression {type(e).__name__}")

    # ------------------------------------------------------------------ code generation
    def tmp(self) -> str:
        self.ntmp += 1
        return f"_t{self.ntmp}"

    def generate(self) -> str:
        self.analyse()
        if self.ret is None:
            raise Unsupported(f"{self.py.__qualname__}: no return")
        args = []
        for a in self.args:
            args.append(a)
            p = self.arg_patterns[a]
            if isinstance(p, frozenset):
                args.extend(f"{a}__d{j}" for j in sorted(p))
        body: list[str] = []
        # locals with a tangent start at zero tangents (a variable first assigned in a branch)
        for v, p in self.pat.items():
            if v in self.args:
                continue
            for j in sorted(p):
                body.append(f"{v}__d{j} = 0.0")
        body.extend(self._stmts(self.fdef.body, 0))
        name = self.out_name()
        lines = [f"def {name}({', '.join(args)}):"]
        lines.extend("    " + ln for ln in body) if body else lines.append("    pass")
        return "\n".join(lines) + "\n"

    def out_name(self) -> str:
        return f"{self.py.__name__}__fwd"

    def _stmts(self, body, ind: int) -> list[str]:
        out: list[str] = []
        pad = "    " * ind
        for st in body:
            if isinstance(st, ast.Expr) and isinstance(st.value, ast.Constant):
                continue  # a docstring
            if isinstance(st, ast.Pass):
                out.append(pad + "pass")
            elif isinstance(st, (ast.Break, ast.Continue)):
                out.append(pad + ast.unparse(st))
            elif isinstance(st, ast.Assign):
                out.extend(pad + ln for ln in self._assign(st.targets[0], st.value))
            elif isinstance(st, ast.AugAssign):
                op = ast.BinOp(left=_name(st.target.id), op=st.op, right=st.value)
                out.extend(pad + ln for ln in self._assign(ast.Name(id=st.target.id, ctx=ast.Store()), op))
            elif isinstance(st, ast.If):
                pre, cond = self._value(st.test)
                out.extend(pad + ln for ln in pre)
                out.append(pad + f"if {cond}:")
                inner = self._stmts(st.body, ind + 1)
                out.extend(inner or [pad + "    pass"])
                if st.orelse:
                    out.append(pad + "else:")
                    out.extend(self._stmts(st.orelse, ind + 1) or [pad + "    pass"])
            elif isinstance(st, ast.For):
                if isinstance(st.iter, ast.Tuple) and all(isinstance(x, ast.Constant) for x in st.iter.elts):
                    pre, it = [], ast.unparse(st.iter)  # a loop over constants
                else:
                    pre, it = self._value(st.iter)
                out.extend(pad + ln for ln in pre)
                out.append(pad + f"for {st.target.id} in {it}:")
                out.extend(self._stmts(st.body, ind + 1) or [pad + "    pass"])
                if st.orelse:
                    raise Unsupported("for-else")
            elif isinstance(st, ast.While):
                pre, cond = self._value(st.test)
                if pre:
                    raise Unsupported("a while condition that calls a jitted function")
                out.append(pad + f"while {cond}:")
                out.extend(self._stmts(st.body, ind + 1) or [pad + "    pass"])
            elif isinstance(st, ast.Return):
                out.extend(pad + ln for ln in self._return(st.value))
            else:
                raise Unsupported(f"statement {type(st).__name__}")
        return out

    def _value(self, e) -> tuple[list[str], str]:
        """Lines computing a value without tangents (a condition, an index), and its expression."""
        lines, v, _ = self.dual(e)
        return lines, v

    def _assign(self, target, value) -> list[str]:
        if isinstance(target, ast.Name):
            lines, v, d = self.dual(value)
            lines.append(f"{target.id} = {v}")
            for j in sorted(self.pat.get(target.id, EMPTY)):
                lines.append(f"{target.id}__d{j} = {d.get(j, '0.0')}")
            return lines
        # a tuple target
        names = [t.id for t in target.elts]
        if isinstance(value, ast.Tuple):
            lines: list[str] = []
            tmps = []
            for e in value.elts:
                ls, v, d = self.dual(e)
                lines.extend(ls)
                t = self.tmp()
                lines.append(f"{t} = {v}")
                td = {}
                for j, dj in d.items():
                    lines.append(f"{t}__d{j} = {dj}")
                    td[j] = f"{t}__d{j}"
                tmps.append((t, td))
            for nm, (t, td) in zip(names, tmps):
                lines.append(f"{nm} = {t}")
                for j in sorted(self.pat.get(nm, EMPTY)):
                    lines.append(f"{nm}__d{j} = {td.get(j, '0.0')}")
            return lines
        lines, results = self._call_tuple(value)
        for nm, (v, d) in zip(names, results):
            lines.append(f"{nm} = {v}")
            for j in sorted(self.pat.get(nm, EMPTY)):
                lines.append(f"{nm}__d{j} = {d.get(j, '0.0')}")
        return lines

    def _return(self, value) -> list[str]:
        if isinstance(value, ast.Tuple):
            lines: list[str] = []
            parts = []
            for e in value.elts:
                ls, v, d = self.dual(e)
                lines.extend(ls)
                parts.append((v, d))
        elif isinstance(value, ast.Call) and self._callee(value) is not None:
            lines, parts = self._call_tuple(value)
        else:
            lines, v, d = self.dual(value)
            parts = [(v, d)]
        flat = []
        for (v, d), p in zip(parts, self.ret):
            flat.append(v)
            flat.extend(d.get(j, "0.0") for j in sorted(p))
        lines.append("return " + (flat[0] if len(flat) == 1 else "(" + ", ".join(flat) + ",)"))
        return lines

    def _call_tuple(self, call: ast.Call):
        """A call of a jitted function: lines, and [(value, tangents)] per returned element."""
        obj = self._callee(call)
        lines: list[str] = []
        argsrc = []
        pats = []
        for a in call.args:
            ap = self._arg_pat(a)
            pats.append(ap)
            ls, v, d = self.dual(a)
            lines.extend(ls)
            argsrc.append(v)
            if isinstance(ap, frozenset):
                argsrc.extend(d.get(j, "0.0") for j in sorted(ap))
        twin, rets = forward_function(obj, tuple(pats), self.seeds, self.direction)
        gname = f"_fwd_{len(self.callees)}"
        self.callees[gname] = (twin, rets)
        t = self.tmp()
        lines.append(f"{t} = {gname}({', '.join(argsrc)})")
        width = sum(1 + len(p) for p in rets)
        results = []
        k = 0
        for p in rets:
            v = f"{t}[{k}]" if width > 1 else t
            d = {}
            for i, j in enumerate(sorted(p)):
                d[j] = f"{t}[{k + 1 + i}]"
            results.append((v, d))
            k += 1 + len(p)
        return lines, results

    def dual(self, e) -> tuple[list[str], str, dict[int, str]]:
        """``(lines, value, {j: tangent})`` for expression ``e``; intermediate values in temporaries."""
        if isinstance(e, ast.Constant):
            return [], repr(e.value), {}
        if isinstance(e, ast.Name):
            p = self.pat.get(e.id, EMPTY)
            p = p if isinstance(p, frozenset) else EMPTY
            return [], e.id, {j: f"{e.id}__d{j}" for j in sorted(p)}
        if isinstance(e, ast.Attribute):
            return [], ast.unparse(e), {}
        if isinstance(e, ast.Subscript):
            pat = self.epat(e)
            ls, v, _ = self.dual(e.value)
            ls2, s, _ = self.dual(e.slice)
            if pat and self.direction is not None:  # the direction's component: p[direction + k]
                return ls + ls2, f"{v}[{s}]", {0: f"{v}[{self.direction + self.static_int(e.slice)}]"}
            return ls + ls2, f"{v}[{s}]", {j: "1.0" for j in pat}
        if isinstance(e, (ast.Compare, ast.BoolOp)) or (isinstance(e, ast.UnaryOp) and isinstance(e.op, ast.Not)):
            # operands may call jitted functions: evaluate them first (their values only)
            return self._plain(e)
        if isinstance(e, ast.UnaryOp):
            ls, v, d = self.dual(e.operand)
            if isinstance(e.op, ast.USub):
                return ls, f"(-{v})", {j: f"(-{dj})" for j, dj in d.items()}
            if isinstance(e.op, ast.UAdd):
                return ls, v, d
            raise Unsupported(f"unary {type(e.op).__name__}")
        if isinstance(e, ast.IfExp):
            lc, c = self._value(e.test)
            ct = self.tmp()
            lines = lc + [f"{ct} = {c}"]
            la, a, da = self.dual(e.body)
            lb, b, db = self.dual(e.orelse)
            t = self.tmp()
            keys = sorted(set(da) | set(db))
            if not la and not lb:
                lines.append(f"{t} = {a} if {ct} else {b}")
                for j in keys:
                    lines.append(f"{t}__d{j} = {da.get(j, '0.0')} if {ct} else {db.get(j, '0.0')}")
            else:  # a branch calls a jitted function: only the branch taken runs, as in the source
                lines.append(f"if {ct}:")
                lines.extend("    " + ln for ln in la)
                lines.append(f"    {t} = {a}")
                lines.extend(f"    {t}__d{j} = {da.get(j, '0.0')}" for j in keys)
                lines.append("else:")
                lines.extend("    " + ln for ln in lb)
                lines.append(f"    {t} = {b}")
                lines.extend(f"    {t}__d{j} = {db.get(j, '0.0')}" for j in keys)
            return lines, t, {j: f"{t}__d{j}" for j in keys}
        if isinstance(e, ast.BinOp):
            return self._binop(e)
        if isinstance(e, ast.Call):
            if self._callee(e) is not None:
                lines, results = self._call_tuple(e)
                if len(results) != 1:
                    raise Unsupported("a tuple-valued call inside an expression")
                v, d = results[0]
                return lines, v, d
            return self._builtin_call(e)
        if isinstance(e, ast.Tuple):
            raise Unsupported("a tuple expression")
        raise Unsupported(f"expression {type(e).__name__}")

    def _plain(self, e) -> tuple[list[str], str, dict]:
        """An expression without tangents whose jitted calls are replaced by their twins' values."""
        lines: list[str] = []

        class R(ast.NodeTransformer):
            def visit_Call(s, node):  # noqa: N805
                if self._callee(node) is not None:
                    ls, v, _ = self.dual(node)
                    lines.extend(ls)
                    return _expr(v)
                s.generic_visit(node)
                return node
        new = R().visit(ast.parse(ast.unparse(e), mode="eval").body)
        return lines, "(" + ast.unparse(new) + ")", {}

    def _binop(self, e: ast.BinOp):
        la, a, da = self.dual(e.left)
        lb, b, db = self.dual(e.right)
        lines = la + lb
        op = e.op
        sym = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**", ast.Mod: "%",
               ast.FloorDiv: "//", ast.BitAnd: "&", ast.BitOr: "|", ast.BitXor: "^"}.get(type(op))
        if sym is None:
            raise Unsupported(f"operator {type(op).__name__}")
        if not da and not db or sym in ("//", "&", "|", "^"):
            return lines, f"({a} {sym} {b})", {}
        t = self.tmp()
        lines.append(f"{t} = {a} {sym} {b}")
        d = {}
        for j in sorted(set(da) | set(db)):
            x, y = da.get(j), db.get(j)
            if sym == "+":
                s = f"{x} + {y}" if x and y else (x or y)
            elif sym == "-":
                s = f"{x} - {y}" if x and y else (x or f"(-{y})")
            elif sym == "*":
                terms = ([f"{x} * {b}"] if x else []) + ([f"{a} * {y}"] if y else [])
                s = " + ".join(terms)
            elif sym == "/":
                s = f"({x} - {t} * {y}) / {b}" if x and y else (f"{x} / {b}" if x else f"(-{t} * {y}) / {b}")
            elif sym == "**":
                terms = []
                if x:
                    terms.append(f"{_dpow(a, b)} * {x}")
                if y:
                    terms.append(f"({t} * math.log({a}) * {y} if {a} > 0.0 else 0.0)")
                s = " + ".join(terms)
            elif sym == "%":
                s = x if x else "0.0"
                if y:
                    s = f"{s} - math.floor({a} / {b}) * {y}"
            lines.append(f"{t}__d{j} = {s}")
            d[j] = f"{t}__d{j}"
        return lines, t, d

    def _builtin_call(self, e: ast.Call):
        fname = _call_name(e)
        lines: list[str] = []
        vals, ders = [], []
        for a in e.args:
            ls, v, d = self.dual(a)
            lines.extend(ls)
            vals.append(v)
            ders.append(d)
        if e.keywords:
            raise Unsupported("keyword arguments")
        func = ast.unparse(e.func)
        if not any(ders) or fname in ("int", "len", "range", "bool", "floor", "ceil", "trunc"):
            return lines, f"{func}({', '.join(vals)})", {}
        t = self.tmp()
        keys = sorted(set().union(*[set(d) for d in ders]))
        d_out = {}
        if fname == "select" and len(vals) == 3:  # brdfkit.engine.select: both values computed, one chosen
            c, a, b = vals
            lines.append(f"{t} = {func}({c}, {a}, {b})")
            for j in sorted(set(ders[1]) | set(ders[2])):
                lines.append(f"{t}__d{j} = {func}({c}, {ders[1].get(j, '0.0')}, {ders[2].get(j, '0.0')})")
                d_out[j] = f"{t}__d{j}"
            return lines, t, d_out
        if fname in ("min", "max") and len(vals) >= 2:
            # fold pairwise; the derivative of the argument Python's rule returns
            cur_v, cur_d = vals[0], ders[0]
            for v2, d2 in zip(vals[1:], ders[1:]):
                t2 = self.tmp()
                ct = self.tmp()
                cmp = "<" if fname == "min" else ">"
                lines.append(f"{ct} = {v2} {cmp} {cur_v}")
                lines.append(f"{t2} = {v2} if {ct} else {cur_v}")
                nd = {}
                for j in sorted(set(cur_d) | set(d2)):
                    lines.append(f"{t2}__d{j} = {d2.get(j, '0.0')} if {ct} else {cur_d.get(j, '0.0')}")
                    nd[j] = f"{t2}__d{j}"
                cur_v, cur_d = t2, nd
            return lines, cur_v, cur_d
        if fname in ("float",) or (func.startswith("numba.") and len(vals) == 1):
            lines.append(f"{t} = {func}({vals[0]})")
            for j in keys:
                lines.append(f"{t}__d{j} = {func}({ders[0][j]})")
                d_out[j] = f"{t}__d{j}"
            return lines, t, d_out
        if fname == "abs" and len(vals) == 1:
            fname, func = "fabs", "abs"
        lines.append(f"{t} = {func}({', '.join(vals)})")
        if (fname in _MATH_UNARY or fname in _QUOTIENT_RULES) and len(vals) == 1:
            x = vals[0]
            if fname in _QUOTIENT_RULES:
                den = _subst(_QUOTIENT_RULES[fname], x, t)
            else:
                g = self.tmp()
                lines.append(f"{g} = {_subst(_MATH_UNARY[fname], x, t)}")
            for j in keys:
                dx = ders[0][j]
                # a derivative that can be infinite meets a zero tangent as 0 (the derivative along a
                # direction that does not move x), not as inf · 0 = nan
                if fname in _QUOTIENT_RULES:
                    d = f"(({dx} / {den} if {den} != 0.0 else math.copysign(math.inf, {dx})) if {dx} != 0.0 else 0.0)"
                elif fname in _UNBOUNDED_RULES:
                    d = f"({g} * {dx} if {dx} != 0.0 else 0.0)"
                else:
                    d = f"{g} * {dx}"
                lines.append(f"{t}__d{j} = {d}")
                d_out[j] = f"{t}__d{j}"
            return lines, t, d_out
        if fname in ("pow", "atan2", "hypot", "copysign") and len(vals) == 2:
            a, b = vals
            da, db = ders
            if fname == "pow":
                ga, gb = _dpow(a, b), f"({t} * math.log({a}) if {a} > 0.0 else 0.0)"
            elif fname == "atan2":  # atan2(y, x)
                q = self.tmp()
                lines.append(f"{q} = {a} * {a} + {b} * {b}")
                ga, gb = f"({b} / {q})", f"(-{a} / {q})"
            elif fname == "hypot":
                ga, gb = f"({a} / {t} if {t} > 0.0 else 0.0)", f"({b} / {t} if {t} > 0.0 else 0.0)"
            else:
                ga, gb = f"math.copysign(1.0, {a}) * math.copysign(1.0, {b})", "0.0"
            for j in keys:
                terms = ([f"{ga} * {da[j]}"] if j in da else []) + ([f"{gb} * {db[j]}"] if j in db else [])
                lines.append(f"{t}__d{j} = {' + '.join(terms)}")
                d_out[j] = f"{t}__d{j}"
            return lines, t, d_out
        raise Unsupported(f"no derivative rule for {func}()")


def _targets(node):
    """The names a statement assigns."""
    if isinstance(node, ast.Assign):
        tg = node.targets
    elif isinstance(node, (ast.AugAssign, ast.For)):
        tg = [node.target]
    else:
        return []
    out = []
    for t in tg:
        out.extend(x for x in ast.walk(t) if isinstance(x, ast.Name))
    return out


def _dpow(a: str, b: str) -> str:
    """∂(a^b)/∂a as source: ``b·a^(b−1)``, and at ``a = 0`` its limit (0 for b > 1, 1 for b = 1, inf for
    0 < b < 1) rather than ``0.0 ** negative``, which raises in Python (the reference engine)."""
    return (f"({b} * {a} ** ({b} - 1.0) if {a} != 0.0 else "
            f"(0.0 if {b} > 1.0 or {b} == 0.0 else (1.0 if {b} == 1.0 else math.inf)))")


def _subst(rule: str, x: str, r: str) -> str:
    """``rule`` with the whole-word names ``x`` and ``r`` replaced."""
    import re
    return re.sub(r"\b([xr])\b", lambda m: x if m.group(1) == "x" else r, rule)


def _call_name(e: ast.Call) -> str:
    f = e.func
    if isinstance(f, ast.Name):
        return f.id
    if isinstance(f, ast.Attribute):
        return f.attr
    return ""


def _module_source(tr: _Func, fsrc: str) -> str:
    head = [
        "# Generated by brdfkit.engine.forward from "
        f"{tr.py.__module__}.{tr.py.__qualname__}; do not edit (rewritten when the source changes).",
        "import importlib",
        "import math",
        "import numba",
        f"_src = importlib.import_module({tr.py.__module__!r})",
        "globals().update({k: v for k, v in vars(_src).items() if not k.startswith('__')})",
        "import math",
        "from brdfkit.engine.forward import _callee_by_key",
    ]
    for gname, (twin, _) in tr.callees.items():
        if id(twin) in _KEY_OF:
            head.append(f"{gname} = _callee_by_key({_KEY_OF[id(twin)]!r})")
        else:  # no tangent flows in: the source function itself
            cp = getattr(twin, "py_func", twin)
            head.append(f"from {cp.__module__} import {cp.__name__} as {gname}")
    head.append("")
    head.append("")
    # inline="never": numba's IR inlining of a twin and its callees (f_conductor's 280 lines once per channel)
    # took 217 s to compile one microfacet configuration cold on the development machine; compiled
    # separately (each twin once, shared by every configuration), 56 s, and 10-18 s for the next ones.
    # A directional twin (one tangent) is small enough to inline (16 s cold for GGX conductor), and only
    # inlined does its driver's loop vectorise across pairs (grad.DIRECTIONAL_TEMPLATE)
    inline = ', inline="always"' if tr.direction is not None else ""
    head.append(f'@numba.njit(cache=True, error_model="numpy", nogil=True{inline})')
    return "\n".join(head) + "\n" + fsrc


_KEY_OF: dict[int, str] = {}
_BY_KEY: dict[str, Callable] = {}


def _callee_by_key(key: str) -> Callable:
    return _BY_KEY[key]


def _pat_str(p) -> str:
    if p == P_ARRAY:
        return "P"
    if isinstance(p, tuple):
        return f"i{p[1]}"
    if not p:
        return "c"
    return "d" + "-".join(str(j) for j in sorted(p))


def _seed_set(seeds) -> frozenset:
    return frozenset(range(seeds)) if isinstance(seeds, int) else frozenset(int(k) for k in seeds)


def _seed_str(seeds: frozenset) -> str:
    """``n17`` for all of ``0 … 16``, else ``s0-3-5``: the seeds in a generated file's name."""
    if seeds == frozenset(range(len(seeds))):
        return f"n{len(seeds)}"
    return "s" + "-".join(str(k) for k in sorted(seeds))


def forward_function(fn: Callable, arg_patterns: tuple, seeds, direction: int | None = None) -> tuple[Callable, tuple]:
    """``(twin, return patterns)``: ``fn``'s forward twin for arguments whose tangent components are
    ``arg_patterns`` (a frozenset per argument, :data:`P_ARRAY` for the parameter array). Where no
    argument carries a tangent, ``fn`` itself (its results carry none). ``seeds``: the indices ``k`` whose
    ``p[k]`` is differentiated (an int ``n``: all of ``0 … n−1``). ``direction``: None, a tangent per seed;
    else ONE tangent, the derivative along the direction whose ``k``-th component is ``p[direction + k]``
    (the caller appends the direction to ``p``)."""
    seeds = _seed_set(seeds)
    py = getattr(fn, "py_func", fn)
    if all(not (p == P_ARRAY or isinstance(p, frozenset) and p) for p in arg_patterns):
        # nothing flows in: the original, its results constants (arity from a trial analysis)
        key = (id(py), arg_patterns, seeds, direction)
        with _LOCK:
            hit = _TWINS.get(key)
            if hit is None:
                tr = _Func(fn, arg_patterns, seeds, direction)
                tr.analyse()
                hit = _TWINS[key] = (fn, tuple(tr.ret or [EMPTY]))
        return hit
    key = (id(py), arg_patterns, seeds, direction)
    with _LOCK:
        hit = _TWINS.get(key)
        if hit is not None:
            return hit
        tr = _Func(fn, arg_patterns, seeds, direction)
        try:
            fsrc = tr.generate()
        except Unsupported as e:
            msg = str(e)
            raise Unsupported(msg if msg.startswith("in ") else f"in {py.__qualname__}: {msg}") from None
        stem = _stem(py, arg_patterns, seeds, direction)
        src = _module_source(tr, fsrc)
        twin = _load(stem, src, tr.out_name())
        _KEY_OF[id(twin)] = stem
        _BY_KEY[stem] = twin
        rets = tuple(tr.ret)
        _TWINS[key] = (twin, rets)
        deps = [_KEY_OF[id(t)] for t, _ in tr.callees.values() if id(t) in _KEY_OF]
        _MADE[stem] = (tr.out_name(), rets, deps, py.__module__)
        return twin, rets


def _stem(py: Callable, arg_patterns: tuple, seeds: frozenset, direction: int | None) -> str:
    """The generated file's name: the source function, seed set, direction and argument patterns."""
    stem = (f"fwd_{py.__module__}_{py.__name__}__{_seed_str(seeds)}{'' if direction is None else f'v{direction}'}__"
            + "_".join(_pat_str(p) for p in arg_patterns))
    stem = stem.replace(".", "_")
    if len(stem) > 180:
        import hashlib
        stem = stem[:120] + "__" + hashlib.sha1(stem.encode()).hexdigest()[:16]
    return stem


#: per generated stem: (function name in its module, return patterns, callee stems, source module)
_MADE: dict[str, tuple[str, tuple, list[str], str]] = {}


def _closure(stem: str) -> list[str]:
    """``stem`` and every twin it calls, callees first (the order their modules must load in)."""
    out: list[str] = []

    def visit(s: str) -> None:
        if s in out:
            return
        for d in _MADE[s][2]:
            visit(d)
        out.append(s)

    visit(stem)
    return out


def _ours(module: str) -> bool:
    """Whether a function of ``module`` is brdfkit's own: its source is in the hash that names the cache folder."""
    return module.split(".")[0] == "brdfkit"


def _manifest_path(stem: str):
    from .cache import cache_dir
    return cache_dir() / "forward" / f"{stem}.json"


def _save_manifest(stem: str) -> None:
    """Record what the analysis of ``stem`` found (its closure's names and return patterns), so a
    later process loads the generated files without analysing the sources again (~0.1 s for
    a microfacet kernel). Only for kernels of the brdfkit package itself: the cache folder is keyed
    by the package's source (:func:`~brdfkit.engine.cache.source_hash`), which a user's kernel is not."""
    import json

    from ..fileio import write_text

    order = _closure(stem)
    if not all(_ours(_MADE[s][3]) for s in order):
        return
    entries = [{"stem": s, "name": _MADE[s][0], "deps": _MADE[s][2], "module": _MADE[s][3],
                "rets": [sorted(r) for r in _MADE[s][1]]} for s in order]
    try:
        write_text(_manifest_path(stem), json.dumps({"closure": entries}))
    except OSError:
        pass


def _load_manifest(stem: str) -> tuple[Callable, tuple] | None:
    """The twin ``stem`` and its return patterns from its manifest and generated files, or None
    (no manifest, or a file missing or unreadable: then the caller analyses the source)."""
    import json

    path = _manifest_path(stem)
    try:
        entries = json.loads(path.read_text())["closure"]
        where = path.parent
        for e in entries:
            s = e["stem"]
            if s not in _BY_KEY:
                src = (where / f"{s}.py").read_text()
                twin = _load(s, src, e["name"])
                _KEY_OF[id(twin)] = s
                _BY_KEY[s] = twin
            _MADE.setdefault(s, (e["name"], tuple(frozenset(r) for r in e["rets"]), list(e["deps"]), e["module"]))
        return _BY_KEY[stem], _MADE[stem][1]
    except (OSError, ValueError, KeyError, TypeError, AttributeError, ImportError):
        return None


def _load(stem: str, src: str, name: str) -> Callable:
    return getattr(load_generated("forward", stem, src, "brdfkit._engine_forward"), name)


def forward_kernel(kernel: Callable, seeds, direction: int | None = None) -> tuple[Callable, tuple]:
    """The forward twin of a model kernel ``kernel(wix, wiy, wiz, wox, woy, woz, p, c)`` seeded by
    ``p[k]`` for each ``k`` in ``seeds`` (an int ``n``: ``p[0..n)``): it returns ``(r, r__d…, g, g__d…,
    b, b__d…)``, with the tangent components of each channel listed in the returned patterns; with a
    ``direction`` (:func:`forward_function`), one tangent per channel at most."""
    pats = (EMPTY,) * 6 + (P_ARRAY, EMPTY)
    seeds = _seed_set(seeds)
    py = getattr(kernel, "py_func", kernel)
    key = (id(py), pats, seeds, direction)
    with _LOCK:
        hit = _TWINS.get(key)
        if hit is None and _ours(py.__module__):
            hit = _load_manifest(_stem(py, pats, seeds, direction))
            if hit is not None:
                _TWINS[key] = hit
        if hit is None:
            hit = forward_function(kernel, pats, seeds, direction)
            stem = _KEY_OF.get(id(hit[0]))
            if stem is not None and stem in _MADE:
                _save_manifest(stem)
    twin, rets = hit
    if len(rets) != 3:
        raise Unsupported("a kernel must return three channels")
    return twin, rets


def pure_forward(fn: Callable) -> Callable:
    """The uncompiled Python function of a generated twin (for the reference engine)."""
    from .reference import pure
    return pure(fn)


__all__ = ["forward_kernel", "forward_function", "Unsupported", "P_ARRAY", "pure_forward"]
