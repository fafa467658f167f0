"""What a name can mean while compiling: classes, objects, variables, modules; and lookup."""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field

from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.builtins import PROPERTY_TYPES, ROOT_CLASS


@dataclass
class ClassInfo:
    """A class: its own property templates (which may hold SelfRef) and its parent."""

    name: str
    parent: ClassInfo | None
    span: Span
    own: dict[str, ir.Expr] = field(default_factory=dict)
    # Default orientation specifiers of the body (`facing: yaw`), templates like `own`.
    own_specifiers: dict[str, ir.Specifier] = field(default_factory=dict)

    def chain(self) -> list[ClassInfo]:
        """This class and its ancestors, most derived first."""
        out, cls = [], self
        while cls is not None:
            out.append(cls)
            cls = cls.parent
        return out

    def defaults(self) -> dict[str, ir.Expr]:
        """Every property's default template, children overriding parents (in root-first order)."""
        merged: dict[str, ir.Expr] = {}
        for cls in reversed(self.chain()):
            merged.update(cls.own)
        return merged

    def default_specifiers(self) -> dict[str, ir.Specifier]:
        """The default orientation specifiers, by their word, children overriding parents."""
        merged: dict[str, ir.Specifier] = {}
        for cls in reversed(self.chain()):
            merged.update(cls.own_specifiers)
        return merged

    def default(self, prop: str) -> ir.Expr | None:
        """The inherited default template of one property, or None."""
        for cls in self.chain():
            if prop in cls.own:
                return cls.own[prop]
        return None

    def properties(self) -> list[str]:
        """Every property an instance has (built-in and declared)."""
        return list(dict.fromkeys([*PROPERTY_TYPES, *self.defaults()]))

    def has(self, prop: str) -> bool:
        """Whether instances have this property."""
        return prop in PROPERTY_TYPES or self.default(prop) is not None

    def accepted_types(self, prop: str) -> frozenset[ir.Type] | None:
        """The static types a value of prop may have (None: unknown property)."""
        if prop in PROPERTY_TYPES:
            return PROPERTY_TYPES[prop]
        default = self.default(prop)
        if default is None:
            return None
        if default.type == ir.Type.ANY:
            return frozenset(ir.Type)
        return frozenset({default.type, ir.Type.ANY})

    def value_type(self, prop: str) -> ir.Type:
        """The static type of reading prop on an instance."""
        if prop == "position":
            return ir.Type.VECTOR
        if prop == "orientation":
            return ir.Type.ANY  # a rotation: only meaningful to the sampler
        if prop in ("x", "y", "z"):
            return ir.Type.SCALAR
        default = self.default(prop)
        if default is not None:
            return default.type
        types = PROPERTY_TYPES.get(prop)
        if types is not None and len(types) == 1:
            return next(iter(types))
        return ir.Type.ANY


@dataclass
class ObjectInfo:
    """A scene object already declared."""

    name: str
    cls: ClassInfo
    span: Span


@dataclass
class VariableInfo:
    """A global variable: its IR name (unique even when a name is rebound) and value."""

    name: str
    value: ir.Expr
    span: Span


@dataclass
class LoopNames:
    """A name a loop body bound: after the loop it means one object per iteration."""

    name: str
    objects: tuple[str, ...]  # the IR names of the objects it named, in iteration order
    span: Span


@dataclass
class ConstantInfo:
    """A named constant (`pi` after `from math import *`)."""

    value: float
    span: Span | None = None


@dataclass
class MathModule:
    """The `math` module bound by `import math`."""

    span: Span | None = None


@dataclass
class SpecModule:
    """A .prs file bound by `import NAME`: its top-level names."""

    name: str
    names: dict[str, object]
    span: Span | None = None


Binding = ClassInfo | ObjectInfo | VariableInfo | ConstantInfo | MathModule | SpecModule | LoopNames


def describe(binding: object) -> str:
    """A binding in words, for messages."""
    if isinstance(binding, ClassInfo):
        return f"the class {binding.name}"
    if isinstance(binding, ObjectInfo):
        cls = binding.cls.name
        return f"the object {binding.name} ({'an' if cls[:1].lower() in 'aeiou' else 'a'} {cls})"
    if isinstance(binding, VariableInfo):
        return f"a variable ({binding.value.type.value})"
    if isinstance(binding, ConstantInfo):
        return "a constant"
    if isinstance(binding, MathModule):
        return "the math module"
    if isinstance(binding, SpecModule):
        return f"the module {binding.name}"
    if isinstance(binding, LoopNames):
        return f"a name bound in a loop body ({', '.join(binding.objects[:3])}{', ...' if len(binding.objects) > 3 else ''})"
    return "a name"


def did_you_mean(name: str, candidates) -> str:
    """`; did you mean 'x'?` for the closest candidate, or ''."""
    close = difflib.get_close_matches(name, sorted(set(candidates)), n=1, cutoff=0.6)
    if not close and name.lower() != name:
        close = [c for c in candidates if c.lower() == name.lower()][:1]
    return f"; did you mean '{close[0]}'?" if close else ""


@dataclass
class Scope:
    """The global namespace shared by a spec and everything it imports."""

    names: dict[str, Binding] = field(default_factory=dict)
    objects: dict[str, ObjectInfo] = field(default_factory=dict)  # every object by IR name
    variables: dict[str, VariableInfo] = field(default_factory=dict)  # every variable by IR name
    assigned_later: dict[str, Span] = field(default_factory=dict)  # every name some statement binds

    def unknown(self, name: str, span: Span, what: str = "name", values_only: bool = True) -> PrscError:
        """The error for a name that is not (yet) bound."""
        if name in self.assigned_later:
            where = self.assigned_later[name]
            return PrscError(f"unknown {what} '{name}': it is defined later (line {where.line}); a name must be "
                             f"defined before it is used", span, notes=((f"'{name}' is defined here", where),))
        if name == "math":
            return PrscError("unknown name 'math': add `import math` before using it", span)
        candidates = [k for k, v in self.names.items() if not (values_only and isinstance(v, ClassInfo))]
        return PrscError(f"unknown {what} '{name}'{did_you_mean(name, candidates)}", span)

    def lookup(self, name: str, span: Span, what: str = "name") -> Binding:
        """The binding of a name, or an 'unknown name' error with a suggestion."""
        try:
            return self.names[name]
        except KeyError:
            raise self.unknown(name, span, what) from None

    def classes(self) -> list[str]:
        """Names bound to classes."""
        return [k for k, v in self.names.items() if isinstance(v, ClassInfo)]


def root_class() -> ClassInfo:
    """`Object`, the implicit root class (its defaults come from prsc.ir.builtins)."""
    return ClassInfo(ROOT_CLASS, None, Span("<builtin>", 1, 1, 1, 1))
