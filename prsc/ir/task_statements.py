"""The task statements of a spec (docs/tasks.md) lowered to prsc.task terms: names resolved
to objects (a class name: any of its objects), numbers folded, each mistake an error at its place."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from prsc.errors import PrscError, Span
from prsc.user_assets.asset_fitting import library_arm
from prsc.ir import model as ir
from prsc.ir.checks import constant_number
from prsc.ir.program import ObjectDecl, TaskLinkRef
from prsc.ir.scope import ClassInfo, LoopNames, ObjectInfo, Scope, VariableInfo, describe
from prsc.syntax import nodes
from prsc.task.terms import DEFAULT_HOLD, DIRECTIONS, Failure, Goal, Record, TaskStatements, Term

STATE_ATTRIBUTES = ("position", "x", "y", "z", "speed", "width", "length", "height")
VECTOR_ATTRIBUTES = ("x", "y", "z")
TASK_NODES = (nodes.GoalStmt, nodes.FailStmt, nodes.TerminateStmt, nodes.RecordStmt)
_WORDS = {"at_rest": "at rest", "in": "in", "on": "on", "touches": "touches", "holds": "holds",
          "upright": "upright", "visible": "visible from"}


def _is_camera(decl: ObjectDecl) -> bool:
    camera, model = decl.prop("camera"), decl.prop("model")
    return (isinstance(camera, ir.Const) and camera.value is True) or (
        isinstance(model, ir.Const) and str(model.value).lower() == "camera")


class TaskLowering:
    """Lowers task statement nodes once every object is declared."""

    def __init__(self, scope: Scope, objects: Sequence[ObjectDecl], resolve: Callable[[nodes.Expr], ir.Expr]):
        self.scope = scope
        self.objects = {o.name: o for o in objects}
        self.resolve = resolve
        self.link_refs: list[TaskLinkRef] = []  # every `X.links["NAME"]` named, read from X's file later

    def statements(self, statements: Sequence[nodes.Statement]) -> TaskStatements:
        """The TaskStatements of the spec's task statement nodes (in source order)."""
        goals, failures, records = [], [], []
        time_limit: float | None = None
        limit_span: Span | None = None
        labels: dict[str, Span] = {}
        names: dict[str, Span] = {}
        for s in statements:
            if isinstance(s, nodes.GoalStmt):
                hold = DEFAULT_HOLD if s.hold is None else self._seconds(s.hold, "a goal's `for`")
                goals.append(Goal(self.predicate(s.condition), hold, s.span.line))
            elif isinstance(s, nodes.FailStmt):
                if s.label in labels:
                    raise PrscError(f'the failure label "{s.label}" is used twice; each failure needs its own',
                                    s.label_span, notes=(("first used here", labels[s.label]),))
                if not s.label.strip():
                    raise PrscError("a failure label may not be empty", s.label_span)
                labels[s.label] = s.label_span
                failures.append(Failure(s.label, self.predicate(s.condition), s.span.line))
            elif isinstance(s, nodes.TerminateStmt):
                if limit_span is not None:
                    raise PrscError("`terminate after` is given twice", s.span, notes=(("first given here", limit_span),))
                time_limit, limit_span = self._seconds(s.seconds, "`terminate after`", positive=True), s.span
            elif isinstance(s, nodes.RecordStmt):
                if s.name in names:
                    raise PrscError(f"'{s.name}' is recorded twice", s.name_span, notes=(("first here", names[s.name]),))
                names[s.name] = s.name_span
                records.append(Record(s.name, s.when, self.term(s.value), s.span.line))
        return TaskStatements(tuple(goals), tuple(failures), time_limit, tuple(records))

    def _seconds(self, expr: nodes.Expr, what: str, positive: bool = False) -> float:
        value = self._constant(expr)
        if value is None:
            raise PrscError(f"the time of {what} must be a constant number of seconds", expr.span)
        if not math.isfinite(value) or value < 0 or (positive and value == 0):
            raise PrscError(f"the time of {what} must be {'positive' if positive else '>= 0'}, not {value:g} seconds",
                            expr.span)
        return value

    def _constant(self, expr: nodes.Expr) -> float | None:
        try:
            return constant_number(self.resolve(expr))
        except PrscError:
            return None

    # ------------------------------------------------------------ expressions

    def predicate(self, expr: nodes.Expr) -> Term:
        """A term that is true or false."""
        term = self.term(expr)
        if not term.is_predicate:
            raise PrscError("expected a condition (a relation, a state word or a comparison), not a value", expr.span)
        return term

    def number(self, expr: nodes.Expr) -> Term:
        """A term that is a number or a vector."""
        term = self.term(expr)
        if term.is_predicate:
            raise PrscError("expected a number here, not a condition", expr.span)
        return term

    def term(self, expr: nodes.Expr) -> Term:
        """Any task expression."""
        if isinstance(expr, nodes.Relation):
            return self._relation(expr)
        if isinstance(expr, nodes.BoolOp):
            return Term(expr.op, tuple(self.predicate(e) for e in expr.operands))
        if isinstance(expr, nodes.UnaryOp) and expr.op == "not":
            return Term("not", (self.predicate(expr.operand),))
        if isinstance(expr, nodes.UnaryOp) and expr.op in "+-":
            inner = self.number(expr.operand)
            return inner if expr.op == "+" else Term("neg", (inner,))
        if isinstance(expr, nodes.Compare):
            parts, left = [], self.number(expr.left)
            for op, right_expr in expr.rest:
                right = self.number(right_expr)
                parts.append(Term("compare", (left, right), name=op))
                left = right
            return parts[0] if len(parts) == 1 else Term("and", tuple(parts))
        if isinstance(expr, nodes.BinOp):
            return Term("arith", (self.number(expr.left), self.number(expr.right)), name=expr.op)
        if isinstance(expr, nodes.Distance):
            return Term("distance", (self.number(expr.source), self.number(expr.target)))
        if isinstance(expr, nodes.Attribute):
            return self._attribute(expr)
        if isinstance(expr, nodes.Index):
            return self._link(expr, None)
        if isinstance(expr, nodes.Bool):
            return Term("true") if expr.value else Term("not", (Term("true"),))
        if isinstance(expr, nodes.Name):
            objects = self._objects(expr, allow_class=False)
            if objects is not None:
                return Term("object", name=objects[0])
        if isinstance(expr, nodes.Call) and isinstance(expr.func, nodes.Name) and expr.func.id in ("Vector3D", "V3D") \
                and len(expr.args) == 3:
            return Term("vector", tuple(self.number(a) for a in expr.args))
        value = self._constant(expr)
        if value is None:
            raise PrscError("a task reads objects' state (relations, touches, at rest, upright, holds, .position, "
                            ".x, .y, .z, .speed), numbers and comparisons; this expression is none of them", expr.span)
        return Term("const", value=value)

    def _attribute(self, expr: nodes.Attribute) -> Term:
        objects = self._objects(expr.target, allow_class=False) if isinstance(expr.target, nodes.Name) else None
        if objects is not None:
            if expr.name not in STATE_ATTRIBUTES:
                raise PrscError(f"a task reads an object's {', '.join(STATE_ATTRIBUTES)}, not '{expr.name}'",
                                expr.name_span)
            return Term("attr", (Term("object", name=objects[0]),), name=expr.name)
        target = self.number(expr.target)
        if expr.name not in VECTOR_ATTRIBUTES:
            raise PrscError(f"a vector has x, y and z, not '{expr.name}'", expr.name_span)
        return Term("attr", (target,), name=expr.name)

    def _objects(self, expr: nodes.Expr, allow_class: bool = True) -> list[str] | None:
        """The objects a name means (one object, or every object of a class), None for a value."""
        if not isinstance(expr, nodes.Name):
            return None
        binding = self.scope.names.get(expr.id)
        if binding is None:
            raise self.scope.unknown(expr.id, expr.span, "object or class", values_only=False)
        if isinstance(binding, ObjectInfo):
            return [binding.name]
        if isinstance(binding, VariableInfo) and isinstance(binding.value, ir.ObjectRef):
            return [binding.value.name]
        if isinstance(binding, LoopNames):
            return list(binding.objects) if allow_class else None
        if isinstance(binding, ClassInfo):
            if not allow_class:
                raise PrscError(f"'{expr.id}' is a class: this needs one object", expr.span)
            chosen = [o.name for o in self.objects.values() if expr.id in o.class_chain]
            if not chosen:
                raise PrscError(f"the scene has no object of class {expr.id}", expr.span)
            return chosen
        return None

    def _link(self, expr: nodes.Index, relation: str | None) -> Term:
        """`X.links["NAME"]`: link NAME of object X, where it is now (its file is read by ir/asset_models.py)."""
        attr = expr.target
        objects = self._objects(attr.target, allow_class=False) \
            if isinstance(attr, nodes.Attribute) and attr.name == "links" else None
        if objects is None:
            raise PrscError('a task names a link as X.links["NAME"], X an object of the scene; this is no link', expr.span)
        name = self.resolve(expr.index)
        if not (isinstance(name, ir.Const) and name.type == ir.Type.STRING):
            raise PrscError('a link is named by a string, as in cabinet.links["drawer"]', expr.index.span)
        self.link_refs.append(TaskLinkRef(objects[0], str(name.value), expr.span, relation))
        return Term("link", (Term("object", name=objects[0]),), name=str(name.value))

    def _operand(self, expr: nodes.Expr, relation: nodes.Relation, camera: bool = False, target: bool = False) -> list[Term]:
        word = _WORDS.get(relation.kind, f"{relation.kind} of")
        if isinstance(expr, nodes.Index):
            # a link is a target where the sampler takes one (`in`, `on`, a direction's), and either side of `touches`
            if (target and relation.kind not in ("visible", "holds")) or relation.kind == "touches":
                return [self._link(expr, ("completely " if relation.completely else "") + relation.kind
                                   if relation.kind in ("in", "on") else None)]
            raise PrscError(f"a link is the target of `{word}`, not its subject: `{word}` reads an object of the scene",
                            expr.span)
        objects = self._objects(expr)
        if objects is None:
            raise PrscError(f"the simulated state decides `{word}` between objects of the scene; this is "
                            f"{describe(self.scope.names.get(expr.id)) if isinstance(expr, nodes.Name) else 'no object'}",
                            expr.span)
        for name in objects:
            if _is_camera(self.objects[name]) != camera:
                raise PrscError(f"`{word}` needs a camera here, and {name} is none" if camera else
                                f"{name} is a camera: a sensor, not a body, so `{word}` cannot hold of it", expr.span)
        return [Term("object", name=name) for name in objects]

    def _check_fingers(self, name: str, span: Span) -> None:
        """`R holds A` reads two finger links of R's gripper: an error here when R names fewer."""
        decl = self.objects[name]
        fingers, model = decl.prop("fingers"), decl.prop("model")
        count = len(fingers.items) if isinstance(fingers, ir.ListExpr) else 0
        arm = library_arm(model.value) if isinstance(model, ir.Const) and not count else None
        count = len(arm.fitting.fingers) if arm is not None else count  # ir/asset_models.py gives them later
        if count < 2:
            raise PrscError(f"`holds` reads two finger links of {name}'s gripper, and {name} names "
                            f"{'none' if not count else 'one'}: a library arm's are known; another robot's file "
                            "gives prsc none to read", span)

    def _relation(self, expr: nodes.Relation) -> Term:
        kind = expr.kind
        subjects = self._operand(expr.subject, expr)
        targets: list[Term | None] = [None]
        if expr.target is not None:
            targets = self._operand(expr.target, expr, camera=kind == "visible", target=True)  # type: ignore[assignment]
        by = () if expr.by is None else (self.number(expr.by),)
        if kind not in DIRECTIONS and by:  # pragma: no cover - the grammar puts `by` on directions only
            raise PrscError(f"`by` goes with a direction, not `{kind}`", expr.by.span)  # type: ignore[union-attr]
        if kind == "holds":
            for subject in subjects:
                self._check_fingers(subject.name, expr.subject.span)  # type: ignore[arg-type]
        terms = []
        for subject in subjects:
            for target in targets:
                if target == subject:
                    raise PrscError(f"{subject.key} is related to itself", expr.span)
                args = (subject,) + (() if target is None else (target,))
                terms.append(Term(kind, args + by, completely=expr.completely))
        return terms[0] if len(terms) == 1 else Term("or", tuple(terms))
