"""AST expressions -> typed IR expressions: name resolution and type checking."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.program import SelfRef
from prsc.ir.builtins import (CONSTRUCTORS, FACE_WORD_GROUPS, FUNCTIONS, MATH_CONSTANTS, PROPERTY_TYPES,
                              SPECIFIER_PROPERTIES)
from prsc.ir.scope import (ClassInfo, ConstantInfo, LoopNames, MathModule, ObjectInfo, Scope, SpecModule,
                           VariableInfo, describe, did_you_mean)
from prsc.ir.constructors import construct
from prsc.ir.type_checks import LOCATED_TYPES, POINT_TYPES, article, expect
from prsc.syntax import nodes

T = ir.Type
def declared_surfaces(cls: ClassInfo) -> tuple[str, ...]:
    """The support-surface lists a class declares: `surfaces: ["boards"]` (constant strings)."""
    default = cls.default("surfaces")
    items = default.items if isinstance(default, ir.ListExpr) else (default,) if default is not None else ()
    return tuple(str(i.value) for i in items if isinstance(i, ir.Const) and i.type == T.STRING)


@dataclass
class DrawIds:
    """Hands out the unique draw_id of every Distribution in a Program."""

    next_id: int = 0

    def take(self) -> int:
        """A fresh draw id."""
        self.next_id += 1
        return self.next_id - 1


@dataclass
class ExprResolver:
    """Resolves expressions in a scope; in a class body `self.prop` becomes SelfRef."""

    scope: Scope
    draws: DrawIds
    self_class: ClassInfo | None = None
    self_props: dict[str, ir.Type] = field(default_factory=dict)  # class body: props known so far

    def resolve(self, expr: nodes.Expr) -> ir.Expr:
        """The IR of one AST expression."""
        method: Callable[[nodes.Expr], ir.Expr] = getattr(self, "_" + type(expr).__name__)
        return method(expr)

    # ------------------------------------------------------------ literals and names

    def _Number(self, e: nodes.Number) -> ir.Expr:
        return ir.Const(e.span, T.SCALAR, e.value)

    def _String(self, e: nodes.String) -> ir.Expr:
        return ir.Const(e.span, T.STRING, e.value)

    def _Bool(self, e: nodes.Bool) -> ir.Expr:
        return ir.Const(e.span, T.BOOL, e.value)

    def _Name(self, e: nodes.Name) -> ir.Expr:
        if e.id == "self" and self.self_class is not None:
            raise PrscError("`self` must be followed by a property, as in self.width", e.span)
        if e.id in FUNCTIONS or e.id in CONSTRUCTORS:
            raise PrscError(f"'{e.id}' is a function: call it, as in {e.id}(...)", e.span)
        binding = self.scope.lookup(e.id, e.span)
        return self._binding_value(binding, e.id, e.span)

    def _binding_value(self, binding, name: str, span: Span) -> ir.Expr:
        if isinstance(binding, VariableInfo):
            if isinstance(binding.value, ir.ObjectRef):
                return ir.ObjectRef(span, T.OBJECT, binding.value.name)
            return ir.VarRef(span, binding.value.type, binding.name)
        if isinstance(binding, ObjectInfo):
            return ir.ObjectRef(span, T.OBJECT, binding.name)
        if isinstance(binding, ConstantInfo):
            return ir.Const(span, T.SCALAR, binding.value)
        if isinstance(binding, ClassInfo):
            raise PrscError(f"'{name}' is a class, not a value: create an object with a statement "
                            f"such as `{name.lower()} = {name} on ...`", span)
        if isinstance(binding, MathModule):
            raise PrscError("'math' is a module: use math.pi, math.sin(x), ...", span)
        if isinstance(binding, SpecModule):
            raise PrscError(f"'{name}' is a module: use {name}.<name>", span)
        if isinstance(binding, LoopNames):
            objects = binding.objects
            which = f"{objects[0]} ... {objects[-1]}" if len(objects) > 1 else "".join(objects)
            raise PrscError(f"'{name}' names one object per iteration of the loop at line {binding.span.line}: "
                            f"after the loop, write one of {which}" if objects else
                            f"'{name}' is bound only inside the loop at line {binding.span.line}", span)
        raise PrscError(f"'{name}' cannot be used here", span)  # pragma: no cover

    # ------------------------------------------------------------ attributes

    def _Attribute(self, e: nodes.Attribute) -> ir.Expr:
        if isinstance(e.target, nodes.Name):
            if e.target.id == "self" and self.self_class is not None:
                return self._self_property(e)
            binding = self.scope.names.get(e.target.id)
            if isinstance(binding, MathModule):
                if e.name in MATH_CONSTANTS:
                    return ir.Const(e.span, T.SCALAR, MATH_CONSTANTS[e.name])
                if e.name in FUNCTIONS:
                    raise PrscError(f"math.{e.name} is a function: call it, as in math.{e.name}(x)", e.span)
                known = [*MATH_CONSTANTS, *FUNCTIONS]
                raise PrscError(f"math has no '{e.name}' a spec may use{did_you_mean(e.name, known)} "
                                f"(allowed: {', '.join(known)})", e.name_span)
            if isinstance(binding, SpecModule):
                if e.name not in binding.names:
                    raise PrscError(f"module {binding.name} has no name '{e.name}'"
                                    f"{did_you_mean(e.name, binding.names)}", e.name_span)
                return self._binding_value(binding.names[e.name], e.name, e.span)
        target = self.resolve(e.target)
        return self.property_of(target, e.name, e.span, e.name_span)

    def property_of(self, target: ir.Expr, prop: str, span: Span, prop_span: Span) -> ir.Expr:
        """`target.prop` with its type; unknown properties are errors."""
        if target.type == T.OBJECT:
            cls = self._object_class(target)
            if cls is None:  # e.g. one of several objects chosen at random
                return ir.PropertyRef(span, _builtin_read_type(prop), target, prop)
            if prop in ("x", "y", "z") or cls.has(prop):
                return ir.PropertyRef(span, cls.value_type(prop), target, prop)
            if prop in declared_surfaces(cls):
                raise PrscError(f"{prop} is a list of support surfaces: pick one by its index, "
                                f"as in {_object_words(target, cls)}.{prop}[0] (the lowest)", prop_span)
            raise PrscError(f"unknown property '{prop}' of {_object_words(target, cls)}"
                            f"{did_you_mean(prop, [*cls.properties(), 'x', 'y', 'z', *declared_surfaces(cls)])}", prop_span)
        if target.type == T.VECTOR:
            if prop in ("x", "y", "z"):
                return ir.PropertyRef(span, T.SCALAR, target, prop)
            raise PrscError(f"a vector has only .x, .y and .z, not '.{prop}'", prop_span)
        if target.type == T.ORIENTED_POINT:
            if prop in ("x", "y", "z"):
                return ir.PropertyRef(span, T.SCALAR, target, prop)
            if prop == "position":
                return ir.PropertyRef(span, T.VECTOR, target, prop)
            if prop == "orientation":
                return ir.PropertyRef(span, T.ANY, target, prop)
            raise PrscError(f"a face point has .position, .orientation, .x, .y and .z, not '.{prop}'", prop_span)
        if target.type == T.ANY:
            return ir.PropertyRef(span, T.ANY, target, prop)
        raise PrscError(f"{article(target.type)} has no property '{prop}'", prop_span)

    def _Index(self, e: nodes.Index) -> ir.Expr:
        attr = e.target
        if isinstance(attr, nodes.Attribute):
            target = self.resolve(attr.target)
            owner = self._object_class(target) if target.type == T.OBJECT else None
            if attr.name == "links" and target.type == T.OBJECT and (owner is None or not owner.has("links")):
                name = self.resolve(e.index)
                if not (isinstance(name, ir.Const) and name.type == T.STRING):
                    raise PrscError('a link is named by a string, as in cabinet.links["drawer"]', e.index.span)
                return ir.LinkRef(e.span, T.REGION, target, str(name.value))
            cls = self._object_class(target) if target.type == T.OBJECT else None
            if cls is not None and attr.name in declared_surfaces(cls) and not cls.has(attr.name):
                index = expect(self.resolve(e.index), {T.SCALAR}, f"the index of {attr.name}")
                return ir.SurfaceRef(e.span, T.REGION, target, attr.name, index)
        self.resolve(attr)  # an unknown property is that error, at its name
        raise PrscError("only a support-surface list can be indexed, as in shelf.boards[1] "
                        "(a class lists its surfaces in `surfaces`)", e.span)

    def _object_class(self, target: ir.Expr) -> ClassInfo | None:
        if isinstance(target, ir.ObjectRef) and target.name in self.scope.objects:
            return self.scope.objects[target.name].cls
        return None

    def _self_property(self, e: nodes.Attribute) -> ir.Expr:
        prop = e.name
        if prop in SPECIFIER_PROPERTIES or prop in ("x", "y", "z"):
            raise PrscError(f"a class default cannot read self.{prop}: position and orientation are set "
                            f"by specifiers, after the properties", e.span)
        if prop in self.self_props:
            return SelfRef(e.span, self.self_props[prop], prop)
        cls = self.self_class
        assert cls is not None
        if cls.has(prop):
            return SelfRef(e.span, cls.value_type(prop), prop)
        known = [*self.self_props, *cls.properties()]
        raise PrscError(f"unknown property '{prop}' of class {cls.name}{did_you_mean(prop, known)}", e.name_span)

    # ------------------------------------------------------------ calls

    def _Call(self, e: nodes.Call) -> ir.Expr:
        func = e.func
        if isinstance(func, nodes.Attribute) and isinstance(func.target, nodes.Name) \
                and isinstance(self.scope.names.get(func.target.id), MathModule):
            if func.name not in FUNCTIONS:
                raise PrscError(f"math has no function '{func.name}' a spec may use"
                                f"{did_you_mean(func.name, FUNCTIONS)} (allowed: {', '.join(FUNCTIONS)})",
                                func.name_span)
            return self._function(func.name, e)
        if not isinstance(func, nodes.Name):
            raise PrscError("only functions, distributions and region constructors can be called", func.span)
        name = func.id
        if name in FUNCTIONS:
            return self._function(name, e)
        if name in CONSTRUCTORS:
            return construct(self, name, e)
        binding = self.scope.names.get(name)
        if isinstance(binding, ClassInfo):
            raise PrscError(f"'{name}' is a class: create an object with a statement such as "
                            f"`{name} on ...`, not {name}(...)", func.span)
        if binding is not None:
            raise PrscError(f"'{name}' is {describe(binding)}, not a function", func.span)
        raise PrscError(f"unknown function '{name}'{did_you_mean(name, [*FUNCTIONS, *CONSTRUCTORS])}", func.span)

    def _function(self, name: str, e: nodes.Call) -> ir.Expr:
        low, high = FUNCTIONS[name]
        n = len(e.args)
        if n < low or (high is not None and n > high):
            want = f"{low}" if low == high else f"at least {low}"
            raise PrscError(f"{name}() takes {want} argument{'s' if (high or 2) > 1 else ''}, got {n}", e.span)
        args = tuple(expect(self.resolve(a), {T.SCALAR}, f"the argument of {name}()") for a in e.args)
        return ir.Call(e.span, T.SCALAR, name, args)

    # ------------------------------------------------------------ operators

    def _BinOp(self, e: nodes.BinOp) -> ir.Expr:
        left, right = self.resolve(e.left), self.resolve(e.right)
        return ir.BinOp(e.span, binop_type(e.op, left, right, e.span), e.op, left, right)

    def _UnaryOp(self, e: nodes.UnaryOp) -> ir.Expr:
        operand = self.resolve(e.operand)
        if e.op == "not":
            expect(operand, {T.BOOL}, "the operand of `not`")
            return ir.UnaryOp(e.span, T.BOOL, "not", operand)
        expect(operand, {T.SCALAR, T.VECTOR, T.ORIENTED_POINT}, f"the operand of unary {e.op}")
        result = T.VECTOR if operand.type == T.ORIENTED_POINT else operand.type
        if e.op == "-" and isinstance(operand, ir.Const) and operand.type == T.SCALAR:
            return ir.Const(e.span, T.SCALAR, -operand.value)
        return ir.UnaryOp(e.span, result, e.op, operand)

    def _Compare(self, e: nodes.Compare) -> ir.Expr:
        left = self.resolve(e.left)
        pairs = []
        for op, right_ast in e.rest:
            right = self.resolve(right_ast)
            if op not in ("==", "!="):
                expect(left, {T.SCALAR}, f"each side of {op}")
                expect(right, {T.SCALAR}, f"each side of {op}")
            span = Span(left.span.path, left.span.line, left.span.column, right.span.end_line,
                        right.span.end_column)
            pairs.append(ir.Compare(span, T.BOOL, op, left, right))
            left = right
        if len(pairs) == 1:  # the whole comparison as written, brackets included
            return ir.Compare(e.span, T.BOOL, pairs[0].op, pairs[0].left, pairs[0].right)
        return ir.BoolOp(e.span, T.BOOL, "and", tuple(pairs))

    def _BoolOp(self, e: nodes.BoolOp) -> ir.Expr:
        operands = tuple(expect(self.resolve(o), {T.BOOL}, f"each operand of `{e.op}`") for o in e.operands)
        return ir.BoolOp(e.span, T.BOOL, e.op, operands)

    def _Degrees(self, e: nodes.Degrees) -> ir.Expr:
        value = expect(self.resolve(e.value), {T.SCALAR}, "an angle in `deg`")
        factor = math.pi / 180.0
        if isinstance(value, ir.Const):
            return ir.Const(e.span, T.SCALAR, value.value * factor)
        return ir.BinOp(e.span, T.SCALAR, "*", value, ir.Const(e.span, T.SCALAR, factor))

    def _FacePoint(self, e: nodes.FacePoint) -> ir.Expr:
        seen: dict[int, str] = {}
        for word in e.words:
            group = next(i for i, g in enumerate(FACE_WORD_GROUPS) if word in g)
            if group in seen:
                raise PrscError(f"a face point names one side per axis: '{seen[group]}' and '{word}' "
                                f"are on the same axis", e.span)
            seen[group] = word
        target = expect(self.resolve(e.target), {T.OBJECT}, f"the target of `{' '.join(e.words)}`")
        words = tuple(seen[g] for g in sorted(seen))
        return ir.FacePoint(e.span, T.ORIENTED_POINT, target, words)

    def _Distance(self, e: nodes.Distance) -> ir.Expr:
        source = expect(self.resolve(e.source), LOCATED_TYPES, "the point after `distance from`")
        target = expect(self.resolve(e.target), LOCATED_TYPES, "the point after `distance from ... to`")
        return ir.Distance(e.span, T.SCALAR, source, target)

    def _RelativeTo(self, e: nodes.RelativeTo) -> ir.Expr:
        value = expect(self.resolve(e.value), POINT_TYPES, "the offset before `relative to`")
        frame = expect(self.resolve(e.frame), LOCATED_TYPES, "the frame after `relative to`")
        return ir.RelativeTo(e.span, T.VECTOR, value, frame)

    def _Pair(self, e: nodes.Pair) -> ir.Expr:
        low = expect(self.resolve(e.low), {T.SCALAR}, "the low end of a (low, high) range")
        high = expect(self.resolve(e.high), {T.SCALAR}, "the high end of a (low, high) range")
        return ir.Distribution(e.span, T.SCALAR, "range", (low, high), self.draws.take())

    def _ListLit(self, e: nodes.ListLit) -> ir.Expr:
        return ir.ListExpr(e.span, T.LIST, tuple(self.resolve(i) for i in e.items))

    def _DictLit(self, e: nodes.DictLit) -> ir.Expr:
        raise PrscError("a {value: weight} mapping is only allowed in Discrete({...}) or Options({...})", e.span)


def _object_words(target: ir.Expr, cls: ClassInfo) -> str:
    if isinstance(target, ir.ObjectRef):
        return f"{target.name} (a {cls.name})"
    return f"a {cls.name}"


def _builtin_read_type(prop: str) -> ir.Type:
    if prop in ("x", "y", "z"):
        return T.SCALAR
    if prop == "position":
        return T.VECTOR
    types = PROPERTY_TYPES.get(prop)
    if types is not None and len(types) == 1:
        return next(iter(types))
    return T.ANY


def binop_type(op: str, left: ir.Expr, right: ir.Expr, span: Span) -> ir.Type:
    """The type of `left op right`, or a type error naming both operand types."""
    lt = T.VECTOR if left.type == T.ORIENTED_POINT else left.type
    rt = T.VECTOR if right.type == T.ORIENTED_POINT else right.type
    allowed = {
        "+": {(T.SCALAR, T.SCALAR): T.SCALAR, (T.VECTOR, T.VECTOR): T.VECTOR},
        "-": {(T.SCALAR, T.SCALAR): T.SCALAR, (T.VECTOR, T.VECTOR): T.VECTOR},
        "*": {(T.SCALAR, T.SCALAR): T.SCALAR, (T.VECTOR, T.SCALAR): T.VECTOR, (T.SCALAR, T.VECTOR): T.VECTOR},
        "/": {(T.SCALAR, T.SCALAR): T.SCALAR, (T.VECTOR, T.SCALAR): T.VECTOR},
    }[op]
    if (lt, rt) in allowed:
        return allowed[(lt, rt)]
    if T.ANY in (lt, rt):
        other = rt if lt == T.ANY else lt
        if other == T.ANY:
            return T.ANY
        results = {res for (a, b), res in allowed.items() if other in (a, b)}
        if results:
            return results.pop() if len(results) == 1 else T.ANY
    verb = {"+": "add", "-": "subtract", "*": "multiply", "/": "divide"}[op]
    raise PrscError(f"cannot {verb} {article(left.type)} and {article(right.type)} ({op})", span)
