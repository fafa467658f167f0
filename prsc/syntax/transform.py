"""The lark parse tree -> AST transformer (prsc.syntax.nodes), keeping every span."""

from __future__ import annotations

import ast as python_ast
import math
import warnings

from lark import Token, Transformer, v_args

from prsc.errors import PrscError, Span
from prsc.syntax import nodes as n


def token_span(path: str, token: Token) -> Span:
    """The span of one token."""
    return Span(path, token.line or 1, token.column or 1, token.end_line or token.line or 1,
                token.end_column or (token.column or 1) + 1)


def _join(first: Span, last: Span) -> Span:
    """The span from the start of first to the end of last."""
    return Span(first.path, first.line, first.column, last.end_line, last.end_column)


def _decode_string(path: str, token: Token) -> str:
    """The value of a string literal (Python escapes; nothing is executed)."""
    try:
        with warnings.catch_warnings():
            # An unknown escape such as "\ " keeps its backslash, as in Python; no warning.
            warnings.simplefilter("ignore")
            value = python_ast.literal_eval(str(token))
    except (SyntaxError, ValueError) as error:
        raise PrscError(f"invalid string literal ({error.msg if isinstance(error, SyntaxError) else error})",
                        token_span(path, token)) from None
    if not isinstance(value, str):  # pragma: no cover - the lexer only passes string tokens
        raise PrscError("invalid string literal", token_span(path, token))
    return value


@v_args(meta=True)
class ToAst(Transformer):
    """Builds prsc.syntax.nodes from a lark tree; one method per grammar rule."""

    def __init__(self, path: str):
        super().__init__(visit_tokens=False)
        self.path = path

    # ------------------------------------------------------------ helpers

    def _span(self, meta) -> Span:
        if getattr(meta, "empty", True):
            return Span(self.path, 1, 1, 1, 1)
        return Span(self.path, meta.line, meta.column, meta.end_line, meta.end_column)

    def _tok(self, token: Token) -> Span:
        return token_span(self.path, token)

    @staticmethod
    def _exprs(children) -> tuple[n.Expr, ...]:
        return tuple(c for c in children if isinstance(c, n.Expr))

    # ------------------------------------------------------------ statements

    def start(self, meta, children):
        statements = tuple(c for c in children if isinstance(c, n.Statement))
        return n.Module(self._span(meta), self.path, statements)

    def import_from(self, meta, children):
        _from, name, _star = children
        return n.ImportFrom(self._span(meta), str(name), self._tok(name))

    def import_module(self, meta, children):
        _import, name = children
        return n.ImportModule(self._span(meta), str(name), self._tok(name))

    def assign(self, meta, children):
        name, value = children
        return n.Assign(self._span(meta), str(name), self._tok(name), value)

    def object_assign(self, meta, children):
        name, cls, *specs = children
        return n.ObjectStmt(self._span(meta), str(name), self._tok(name), str(cls), self._tok(cls), tuple(specs))

    def object_stmt(self, meta, children):
        cls, *specs = children
        return n.ObjectStmt(self._span(meta), None, None, str(cls), self._tok(cls), tuple(specs))

    def param_stmt(self, meta, children):
        return n.ParamStmt(self._span(meta), tuple(c for c in children if isinstance(c, tuple)))

    def param_item(self, meta, children):
        name, value = children
        return (str(name), self._tok(name), value)

    def require_stmt(self, meta, children):
        exprs = self._exprs(children)
        probability, condition = (exprs[0], exprs[1]) if len(exprs) == 2 else (None, exprs[0])
        return n.RequireStmt(self._span(meta), condition, probability)

    # ------------------------------------------------------------ the task (docs/tasks.md)

    def goal_stmt(self, meta, children):
        _goal, condition, _for, hold = children[:4]
        return n.GoalStmt(self._span(meta), condition, hold)

    def fail_stmt(self, meta, children):
        _fail, label, _when, condition = children
        return n.FailStmt(self._span(meta), _decode_string(self.path, label), self._tok(label), condition)

    def terminate_stmt(self, meta, children):
        return n.TerminateStmt(self._span(meta), self._exprs(children)[0])

    def record_stmt(self, meta, children):
        _record, when, value, _as, name = children
        return n.RecordStmt(self._span(meta), str(when) if when is not None else "step", value, str(name),
                            self._tok(name))

    def _relation(self, meta, kind, subject, target, word, completely=False, by=None):
        return n.Relation(self._span(meta), kind, subject, target, completely, by, self._tok(word))

    def relation_in(self, meta, children):
        subject, completely, word, target = children
        return self._relation(meta, "in", subject, target, word, completely is not None)

    def relation_on(self, meta, children):
        subject, completely, word, target = children
        return self._relation(meta, "on", subject, target, word, completely is not None)

    def task_direction(self, meta, children):
        return children[0]

    def relation_direction(self, meta, children):
        subject, word, target, _by, amount = children
        return self._relation(meta, str(word), subject, target, word, by=amount)

    def relation_touches(self, meta, children):
        subject, word, target = children
        return self._relation(meta, "touches", subject, target, word)

    def relation_holds(self, meta, children):
        subject, word, target = children
        return self._relation(meta, "holds", subject, target, word)

    def relation_at_rest(self, meta, children):
        subject, word, _rest = children
        return self._relation(meta, "at_rest", subject, None, word)

    def relation_upright(self, meta, children):
        subject, word = children
        return self._relation(meta, "upright", subject, None, word)

    def relation_visible(self, meta, children):
        subject, word, _from, camera = children
        return self._relation(meta, "visible", subject, camera, word)

    def expr_stmt(self, meta, children):
        return n.ExprStmt(self._span(meta), children[0])

    def class_def(self, meta, children):
        names = [c for c in children if isinstance(c, Token) and c.type == "NAME"]
        props = tuple(c for c in children if isinstance(c, n.ClassProperty))
        specs = tuple(c for c in children if isinstance(c, n.ClassSpecifier))
        parent = names[1] if len(names) > 1 else None
        return n.ClassDef(self._span(meta), str(names[0]), self._tok(names[0]),
                          str(parent) if parent is not None else None,
                          self._tok(parent) if parent is not None else None, props, specs)

    def class_specifier(self, meta, children):
        word, value = children
        return n.ClassSpecifier(self._span(meta), str(word), value)

    def for_loop(self, meta, children):
        _for, var, _in, function, _lpar, *rest = children
        args = tuple(c for c in rest if isinstance(c, n.Expr))
        body = tuple(c for c in rest if isinstance(c, n.Statement))
        return n.ForLoop(self._span(meta), str(var), self._tok(var), str(function), self._tok(function), args, body)

    def class_property(self, meta, children):
        name, value = children
        return n.ClassProperty(self._span(meta), str(name), value)

    def class_doc(self, meta, children):
        return None

    # ------------------------------------------------------------ specifiers

    def with_spec(self, meta, children):
        _with, name, value = children
        return n.WithSpec(self._span(meta), str(name), self._tok(name), value)

    def joint_spec(self, meta, children):
        _with, _joint, name, value = children
        return n.JointSpec(self._span(meta), _decode_string(self.path, name), self._tok(name), value)

    def at_spec(self, meta, children):
        return n.AtSpec(self._span(meta), children[-1])

    def in_spec(self, meta, children):
        return n.InSpec(self._span(meta), children[-1], children[0] is not None)

    def on_spec(self, meta, children):
        return n.OnSpec(self._span(meta), children[-1], children[0] is not None)

    def direction_word(self, meta, children):
        return str(children[0])

    def direction_spec(self, meta, children):
        relation, target, _by, amount = children
        return n.DirectionSpec(self._span(meta), relation, target, amount)

    def beyond_spec(self, meta, children):
        target, amount, origin = self._exprs(children)
        return n.BeyondSpec(self._span(meta), target, amount, origin)

    def aligned_spec(self, meta, children):
        target = children[1]
        axis = children[-1]
        text = _decode_string(self.path, axis) if axis.type == "STRING" else str(axis)
        return n.AlignedSpec(self._span(meta), target, text, self._tok(axis))

    def facing_spec(self, meta, children):
        return n.FacingSpec(self._span(meta), children[-1])

    def facing_toward_spec(self, meta, children):
        return n.FacingTowardSpec(self._span(meta), children[-1])

    def reachable_spec(self, meta, children):
        return n.ReachableSpec(self._span(meta), children[-1])

    def stably_spec(self, meta, children):
        return n.StablySpec(self._span(meta), children[-1])

    def visible_spec(self, meta, children):
        return n.VisibleSpec(self._span(meta), children[-1], children[0] is not None)

    # ------------------------------------------------------------ expressions

    def _chain(self, meta, children, make):
        """Fold `a op b op c` left to right without recursion."""
        result = children[0]
        for i in range(1, len(children), 2):
            op, right = children[i], children[i + 1]
            result = make(_join(result.span, right.span), str(op), result, right)
        return result

    def or_expr(self, meta, children):
        return n.BoolOp(self._span(meta), "or", tuple(children))

    def and_expr(self, meta, children):
        return n.BoolOp(self._span(meta), "and", tuple(children))

    def not_op(self, meta, children):
        return n.UnaryOp(self._span(meta), "not", children[-1])

    def comparison(self, meta, children):
        rest = tuple((str(children[i]), children[i + 1]) for i in range(1, len(children), 2))
        return n.Compare(self._span(meta), children[0], rest)

    def relative(self, meta, children):
        result = children[0]
        for frame in children[1:]:
            result = n.RelativeTo(_join(result.span, frame.span), result, frame)
        return result

    def sum(self, meta, children):
        return self._chain(meta, children, n.BinOp)

    def term(self, meta, children):
        return self._chain(meta, children, n.BinOp)

    def unary(self, meta, children):
        sign, operand = children
        return n.UnaryOp(self._span(meta), str(sign), operand)

    def face(self, meta, children):
        word, inner = children
        if isinstance(inner, n.FacePoint) and not inner.words_closed:
            return n.FacePoint(self._span(meta), (str(word),) + inner.words, inner.target)
        return n.FacePoint(self._span(meta), (str(word),), inner)

    def distance(self, meta, children):
        _distance, _from, source, target = children
        return n.Distance(self._span(meta), source, target)

    def degrees(self, meta, children):
        return n.Degrees(self._span(meta), children[0])

    def attribute(self, meta, children):
        target, name = children
        return n.Attribute(self._span(meta), target, str(name), self._tok(name))

    def index(self, meta, children):
        target, index = self._exprs(children)
        return n.Index(self._span(meta), target, index)

    def call(self, meta, children):
        func = children[0]
        return n.Call(self._span(meta), func, self._exprs(children[1:]))

    def number(self, meta, children):
        value = float(children[0])
        if not math.isfinite(value):  # 1e400 reads as infinity: no length or angle is that
            raise PrscError(f"number {children[0]} is too large", self._span(meta))
        return n.Number(self._span(meta), value)

    def string(self, meta, children):
        return n.String(self._span(meta), _decode_string(self.path, children[0]))

    def true(self, meta, children):
        return n.Bool(self._span(meta), True)

    def false(self, meta, children):
        return n.Bool(self._span(meta), False)

    def name(self, meta, children):
        return n.Name(self._span(meta), str(children[0]))

    def group(self, meta, children):
        inner = children[1]
        if isinstance(inner, n.FacePoint):
            # `(top back t)`: a finished face point; a word before it starts a new one
            return n.FacePoint(self._span(meta), inner.words, inner.target, words_closed=True)
        return inner

    def range(self, meta, children):
        low, high = self._exprs(children)
        return n.Pair(self._span(meta), low, high)

    def list(self, meta, children):
        return n.ListLit(self._span(meta), self._exprs(children))

    def dict(self, meta, children):
        return n.DictLit(self._span(meta), tuple(c for c in children if isinstance(c, tuple)))

    def dict_item(self, meta, children):
        return (children[0], children[1])
