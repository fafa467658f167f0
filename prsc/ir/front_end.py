"""The front end's entry point: a spec path -> prsc.ir.model.Program."""

from __future__ import annotations

import dataclasses
import os
from typing import Sequence

from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.program import ClassDef, ObjectDecl, Param, Program, Require, SelfRef, Variable
from prsc.ir.builtins import (BUILTIN_SPAN, MATH_CONSTANTS, OBJECT_DEFAULTS, PROPERTY_TYPES, ROOT_CLASS,
                              SPECIFIER_PROPERTIES)
from prsc.ir.checks import check_values, constant_number
from prsc.ir.expressions import DrawIds, ExprResolver
from prsc.ir.type_checks import article, expect, type_words
from prsc.ir.imports import MATH, ModuleGraph, load_module_graph
from prsc.ir.loops import LoopStatements, bound_names, iteration_name
from prsc.ir.asset_models import with_asset_models
from prsc.ir.mesh_sizes import with_mesh_sizes
from prsc.ir.textures import with_textures
from prsc.ir.order import order_properties, order_specifiers
from prsc.ir.scope import (ClassInfo, ConstantInfo, MathModule, ObjectInfo, Scope, SpecModule,
                           VariableInfo, describe, did_you_mean)
from prsc.ir.specifiers import lower_specifier
from prsc.ir.task_statements import TASK_NODES, TaskLowering
from prsc.ir.walk import rebuild, referenced_objects, referenced_variables, specifier_exprs
from prsc.syntax import nodes

T = ir.Type


def _root_class() -> ClassInfo:
    """`Object` with the built-in defaults of docs/language.md section 11."""
    cls = ClassInfo(ROOT_CLASS, None, BUILTIN_SPAN)
    for prop, value in OBJECT_DEFAULTS:
        kind = T.BOOL if isinstance(value, bool) else T.STRING if isinstance(value, str) else T.SCALAR
        cls.own[prop] = ir.Const(BUILTIN_SPAN, kind, value)
    return cls


def _statement_names(module: nodes.Module) -> dict[str, Span]:
    """Names a module binds, with where (anonymous objects must not take them)."""
    out: dict[str, Span] = {}
    bound_names(module.statements, (), out)
    return out


class Compiler(LoopStatements):
    """Walks the statements of a spec (imports inline, each file once) and builds the Program."""

    def __init__(self, graph: ModuleGraph):
        self.graph = graph
        self.scope = Scope()
        root = _root_class()
        self.scope.names[ROOT_CLASS] = root
        self.classes: list[ClassInfo] = [root]
        self.draws = DrawIds()
        self.objects: list[ObjectDecl] = []
        self.variables: list[Variable] = []
        self.params: dict[str, Param] = {}
        self.requires: list[Require] = []
        self.workspace: ir.Expr | None = None
        self.executed: set[str] = set()
        self.exports: dict[str, dict[str, object]] = {}
        self.current: list[str] = []
        self.binding_spans: dict[str, Span] = {}
        for module in graph.modules.values():
            for name, span in _statement_names(module).items():
                self.scope.assigned_later.setdefault(name, span)
        self.reserved = set(self.scope.assigned_later)
        self.anonymous_counts: dict[str, int] = {}
        self.variable_versions: dict[str, int] = {}
        self.variable_objects: dict[str, set[str]] = {}
        self.iterations: tuple[int, ...] = ()  # the iteration number of each enclosing loop
        self.iterations_used = 0
        self.task_nodes: list[nodes.Statement] = []

    # ------------------------------------------------------------ driving

    def run(self) -> Program:
        """Compile the main module and everything it imports."""
        main = self.graph.modules[self.graph.main]
        if not main.statements:
            raise PrscError("empty spec: the file has no statements", Span(main.path, 1, 1, 1, 1))
        self._execute(self.graph.main)
        lowering = TaskLowering(self.scope, self.objects, lambda e: ExprResolver(self.scope, self.draws).resolve(e))
        task = lowering.statements(self.task_nodes)
        return Program(
            task=task,
            task_links=tuple(lowering.link_refs),
            path=main.path,
            objects=tuple(self.objects),
            variables=tuple(self.variables),
            params=tuple(self.params.values()),
            requires=tuple(self.requires),
            workspace=self.workspace,
            classes=tuple(ClassDef(c.name, c.parent.name if c.parent else None, tuple(c.defaults().items()),
                                      c.span, tuple(c.default_specifiers().values())) for c in self.classes),
            source_files=tuple(self.graph.modules[p].path for p in self.graph.order),
            sources=tuple((self.graph.modules[p].path, self.graph.modules[p].source) for p in self.graph.order),
        )

    def _execute(self, real: str) -> None:
        self.executed.add(real)
        self.exports[real] = {}
        self.current.append(real)
        for statement in self.graph.modules[real].statements:
            try:
                self._statement(statement)
            except RecursionError:
                raise PrscError("this statement is nested too deeply to compile", statement.span) from None
        self.current.pop()

    def _bind(self, name: str, binding, span: Span) -> None:
        existing = self.scope.names.get(name)
        if isinstance(existing, (ClassInfo, ObjectInfo)):
            first = self.binding_spans.get(name)
            raise PrscError(f"'{name}' is already defined as {describe(existing)}", span,
                            notes=((f"'{name}' is first defined here", first),) if first else ())
        self.scope.names[name] = binding
        self.binding_spans[name] = span
        self.exports[self.current[-1]][name] = binding

    # ------------------------------------------------------------ statements

    def _statement(self, s: nodes.Statement) -> None:
        if isinstance(s, (nodes.ImportFrom, nodes.ImportModule)):
            self._import(s)
        elif isinstance(s, nodes.ClassDef):
            self._class(s)
        elif isinstance(s, nodes.ObjectStmt):
            self._object(s.name, s.name_span, s.class_name, s.class_span, s.specifiers, s.span)
        elif isinstance(s, nodes.Assign):
            self._assign(s)
        elif isinstance(s, nodes.ParamStmt):
            self._param(s)
        elif isinstance(s, nodes.RequireStmt):
            self._require(s)
        elif isinstance(s, nodes.ExprStmt):
            self._expression_statement(s)
        elif isinstance(s, TASK_NODES):
            self.task_nodes.append(s)  # lowered once every object is declared (a task may name any)
        elif isinstance(s, nodes.ForLoop):
            self._loop(s)
        else:  # pragma: no cover
            raise PrscError("unsupported statement", s.span)

    def _import(self, s: nodes.ImportFrom | nodes.ImportModule) -> None:
        target = self.graph.targets[id(s)]
        if target == MATH:
            if isinstance(s, nodes.ImportModule):
                self._bind("math", MathModule(s.span), s.span)
            else:
                for name, value in MATH_CONSTANTS.items():
                    self._bind(name, ConstantInfo(value, s.span), s.span)
            return
        if target not in self.executed:
            self._execute(target)
        if isinstance(s, nodes.ImportModule):
            self._bind(s.module, SpecModule(s.module, dict(self.exports[target]), s.span), s.span)
        elif target in self.exports and self.current[-1] != target:
            # names the imported file bound are visible (the namespace is shared); re-export them
            self.exports[self.current[-1]].update(self.exports[target])

    def _assign(self, s: nodes.Assign) -> None:
        value_ast = s.value
        if isinstance(value_ast, nodes.Name) and isinstance(self.scope.names.get(value_ast.id), ClassInfo):
            self._object(s.target, s.target_span, value_ast.id, value_ast.span, (), s.span)
            return
        if s.target in (ROOT_CLASS, "self"):
            raise PrscError(f"'{s.target}' cannot be assigned", s.target_span)
        value = ExprResolver(self.scope, self.draws).resolve(value_ast)
        if s.target == "workspace" and value.type not in (T.REGION, T.ANY):
            raise PrscError(f"workspace must be a region, not {article(value.type)}", value.span)
        if isinstance(value, ir.ObjectRef):  # an alias of an object
            self._bind(s.target, VariableInfo(s.target, value, s.span), s.target_span)
            return
        version = self.variable_versions.get(s.target, 0) + 1
        self.variable_versions[s.target] = version
        ir_name = s.target if version == 1 else f"{s.target}#{version}"
        info = VariableInfo(ir_name, value, s.span)
        self.scope.variables[ir_name] = info
        self.variable_objects[ir_name] = self._objects_of(value)
        self.variables.append(Variable(ir_name, value, s.span))
        self._bind(s.target, info, s.target_span)
        if s.target == "workspace":
            self.workspace = value

    def _param(self, s: nodes.ParamStmt) -> None:
        for name, span, value_ast in s.items:
            if name in self.params:
                raise PrscError(f"param '{name}' is set twice", span,
                                notes=(("first set here", self.params[name].span),))
            value = ExprResolver(self.scope, self.draws).resolve(value_ast)
            self.params[name] = Param(name, value, span)

    def _require(self, s: nodes.RequireStmt) -> None:
        resolver = ExprResolver(self.scope, self.draws)
        probability = 1.0
        if s.probability is not None:
            p_expr = resolver.resolve(s.probability)
            p = constant_number(p_expr)
            if p is None:
                raise PrscError("the probability in require[p] must be a constant number", p_expr.span)
            if not 0.0 <= p <= 1.0:
                raise PrscError(f"the probability in require[p] must lie in [0, 1], not {p:g}", p_expr.span)
            probability = p
        condition = resolver.resolve(s.condition)
        if condition.type not in (T.BOOL, T.ANY):
            raise PrscError(f"require needs a condition (true or false), not {article(condition.type)}",
                            condition.span)
        self.requires.append(Require(condition, probability, s.span))

    def _expression_statement(self, s: nodes.ExprStmt) -> None:
        value = s.value
        if isinstance(value, nodes.String):
            return  # a docstring
        if isinstance(value, nodes.Name):
            binding = self.scope.names.get(value.id)
            if isinstance(binding, ClassInfo):
                self._object(None, None, value.id, value.span, (), s.span)
                return
            if binding is None:
                raise self.scope.unknown(value.id, value.span, "class or name", values_only=False)
        raise PrscError("this expression does nothing on its own: a statement creates an object "
                        "(`Cube on table`), assigns (`x = ...`), or is param, require or an import", s.span)

    # ------------------------------------------------------------ classes

    def _class(self, s: nodes.ClassDef) -> None:
        if s.parent is None:
            parent = self.scope.names[ROOT_CLASS]
        else:
            parent = self.scope.names.get(s.parent)
            if parent is None:
                if s.parent in self.scope.assigned_later:
                    raise self.scope.unknown(s.parent, s.parent_span, "class")
                raise PrscError(f"unknown class '{s.parent}'{did_you_mean(s.parent, self.scope.classes())}",
                                s.parent_span)
            if not isinstance(parent, ClassInfo):
                raise PrscError(f"'{s.parent}' is {describe(parent)}, not a class", s.parent_span)
        info = ClassInfo(s.name, parent, s.name_span)
        resolver = ExprResolver(self.scope, self.draws, self_class=info,
                                self_props={p.name: T.ANY for p in s.properties})
        first: dict[str, Span] = {}
        for prop in s.properties:
            if prop.name in first:
                raise PrscError(f"duplicate property '{prop.name}' in class {s.name}", prop.span,
                                notes=((f"'{prop.name}' is first defined here", first[prop.name]),))
            first[prop.name] = prop.span
            if prop.name in SPECIFIER_PROPERTIES:
                hint = "; for a default yaw write `facing: (0, 360 deg)`" if prop.name == "orientation" else ""
                raise PrscError(f"a class cannot give {prop.name} a default: it is set by specifiers "
                                f"(at, on, in, facing, ...){hint}", prop.span)
            value = resolver.resolve(prop.value)
            accepted = PROPERTY_TYPES.get(prop.name)
            if accepted is not None and value.type != T.ANY and value.type not in accepted:
                raise PrscError(f"property {prop.name} needs {type_words(accepted)}, not {article(value.type)}",
                                value.span)
            info.own[prop.name] = value
            resolver.self_props[prop.name] = value.type
        for spec in s.specifiers:
            if spec.word in info.own_specifiers:
                raise PrscError(f"duplicate `{spec.word}:` in class {s.name}", spec.span,
                                notes=(("first given here", info.own_specifiers[spec.word].span),))
            direction = expect(resolver.resolve(spec.value), {T.VECTOR, T.SCALAR},
                               "the default after `facing:` (a vector, or a yaw angle)")
            info.own_specifiers[spec.word] = ir.Facing(spec.span, ("orientation",), (), direction)
        templates = info.defaults()
        order_properties(templates, {k: v.span for k, v in templates.items()}, None, s.name)  # cycles
        self._bind(s.name, info, s.name_span)
        self.classes.append(info)

    # ------------------------------------------------------------ objects

    def _anonymous_name(self, cls: ClassInfo) -> str:
        base = cls.name.lower()
        k = self.anonymous_counts.get(base, 0)
        while True:
            k += 1
            name = f"{base}_{k}"
            if name not in self.reserved and name not in self.scope.names and name not in self.scope.objects:
                self.anonymous_counts[base] = k
                return name

    def _instantiate(self, template: ir.Expr, object_name: str) -> ir.Expr:
        """A class default for one object: self.prop -> that object's prop, fresh draw ids."""
        fresh: dict[int, int] = {}

        def replace(node: ir.Expr) -> ir.Expr | None:
            if isinstance(node, SelfRef):
                return ir.PropertyRef(node.span, node.type, ir.ObjectRef(node.span, T.OBJECT, object_name), node.prop)
            if isinstance(node, ir.Distribution):
                if node.draw_id not in fresh:
                    fresh[node.draw_id] = self.draws.take()
                return ir.Distribution(node.span, node.type, node.kind, node.args, fresh[node.draw_id], node.weights)
            return None

        return rebuild(template, replace)

    def _objects_of(self, expr: ir.Expr) -> set[str]:
        """Objects an expression depends on, through variables too."""
        found = set(referenced_objects(expr))
        for var in referenced_variables(expr):
            found |= self.variable_objects.get(var, set())
        return found

    def _object(self, name: str | None, name_span: Span | None, class_name: str, class_span: Span,
                specifier_asts: Sequence[nodes.Specifier], span: Span) -> None:
        binding = self.scope.names.get(class_name)
        if not isinstance(binding, ClassInfo):
            if binding is None:
                if class_name in self.scope.assigned_later:
                    raise self.scope.unknown(class_name, class_span, "class")
                raise PrscError(f"unknown class '{class_name}'{did_you_mean(class_name, self.scope.classes())}",
                                class_span)
            raise PrscError(f"'{class_name}' is {describe(binding)}, not a class; an object statement "
                            f"starts with a class name", class_span)
        cls = binding
        if name is not None:
            if name in ("workspace", ROOT_CLASS, "self"):
                raise PrscError(f"'{name}' cannot name an object", name_span)
            existing = self.scope.names.get(name)
            if isinstance(existing, (ClassInfo, ObjectInfo)):
                self._bind(name, None, name_span)  # raises "already defined"
        object_name = name if name is not None else self._anonymous_name(cls)
        if name is not None and self.iterations:
            object_name = iteration_name(name, self.iterations)
        resolver = ExprResolver(self.scope, self.draws)
        specifiers = [lower_specifier(resolver, cls, s) for s in specifier_asts]
        if not any("orientation" in spec.sets for spec in specifiers):
            # the class's default orientation specifiers (`facing:` in its body), drawn afresh
            for default in cls.default_specifiers().values():
                specifiers.append(self._instantiate_specifier(default, object_name))
        overrides: dict[str, ir.With] = {}
        for spec in specifiers:
            if isinstance(spec, ir.With) and spec.prop not in SPECIFIER_PROPERTIES:
                if spec.prop in overrides:
                    first = overrides[spec.prop]
                    raise PrscError(f"{spec.prop} is set twice on this object", spec.span,
                                    notes=(("first set here", first.span),))
                overrides[spec.prop] = spec
        properties: dict[str, ir.Expr] = {}
        spans: dict[str, Span] = {}
        for prop, template in cls.defaults().items():
            if prop in overrides:
                continue
            properties[prop] = self._instantiate(template, object_name)
            spans[prop] = template.span
        for prop, spec in overrides.items():
            properties[prop] = spec.value
            spans[prop] = spec.span
        ordered_properties = order_properties(properties, spans, object_name, cls.name)
        ordered_specifiers = order_specifiers(specifiers)
        depends: set[str] = set()
        for _, value in ordered_properties:
            depends |= self._objects_of(value)
        for spec in ordered_specifiers:
            for expr in specifier_exprs(spec):
                depends |= self._objects_of(expr)
        depends.discard(object_name)
        order = {o.name: i for i, o in enumerate(self.objects)}
        decl = ObjectDecl(
            name=object_name,
            class_name=cls.name,
            anonymous=name is None,
            span=span,
            properties=ordered_properties,
            specifiers=ordered_specifiers,
            depends_on=tuple(sorted(depends, key=lambda o: order.get(o, -1))),
            class_chain=tuple(c.name for c in cls.chain()),
        )
        self.objects.append(decl)
        info = ObjectInfo(object_name, cls, span)
        self.scope.objects[object_name] = info
        if name is not None:
            self._bind(name, info, name_span)
            if object_name != name:
                self._bind(object_name, info, name_span)

    def _instantiate_specifier(self, template: ir.Specifier, object_name: str) -> ir.Specifier:
        """A class's default specifier for one object (see _instantiate)."""
        changes = {f.name: self._instantiate(getattr(template, f.name), object_name)
                   for f in dataclasses.fields(template) if isinstance(getattr(template, f.name), ir.Expr)}
        return dataclasses.replace(template, **changes)


def compile_program(path: str, include_dirs: Sequence[str] = ()) -> Program:
    """Parse, resolve imports and names, type-check and order a spec: the Program IR."""
    path = os.fspath(path)
    try:
        graph = load_module_graph(path, include_dirs)
        program = with_asset_models(with_mesh_sizes(Compiler(graph).run(), include_dirs), include_dirs)
        program = with_textures(program, include_dirs)
        check_values(program)
        return program
    except RecursionError:
        raise PrscError("the spec is nested too deeply to compile", Span(path, 1, 1, 1, 1)) from None
