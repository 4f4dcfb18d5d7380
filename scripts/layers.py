"""Check the floors of ``src/plausible``: import cycles, upward imports, long functions, CLI flags in library errors.

    PYTHONPATH=src python scripts/layers.py            # the report; exit status 1 when anything is found
    python scripts/layers.py path/to/package          # another package (the tests feed it broken ones)

An AST walk of every module, imports inside functions included (``import x``, ``from x import y``,
relative imports; ``from pkg import name`` counts as an import of ``pkg.name`` when that is a module,
else of ``pkg``). It reports

* **cycles**: strongly connected components of the module graph (a package's ``__init__`` is the
  package's own node; importing ``a.b.c`` is an edge to ``a.b.c`` only, not to ``a`` and ``a.b``,
  whose ``__init__`` Python runs first: otherwise every module would reach the top-level face);
* **floors**: the imports that :data:`FORBIDDEN` rules out (issue 33's "Done when": a model is below
  every user of models; rendering is below fitting and figures; the vector math is below the contract);
* **long functions**: ``def`` bodies over :data:`MAX_LINES` lines (from ``def`` to the last line);
* **flags**: ``"--name"`` in a string of a ``raise`` outside :data:`FLAG_OWNERS` (a library error
  names the argument; the CLI maps it to its flag);
* **material**: the string ``"material:"`` outside the catalogue package (one owner of the concept;
  error messages that list the accepted forms aside);
* **kinds**: ``x.kind`` compared (``==``, ``!=``, ``in``, ``not in``) with one of :data:`PARAM_KINDS`
  written as a string (or a tuple of strings) outside :data:`KIND_OWNER`: a parameter's kind owns its
  conversions (``Param.parse``, ``to_mitsuba``, ``traversal``, ...) and says what it is
  (``is_color``, ``numeric``, ``nests_model``), so no caller branches on the name.  A lookup in a
  table of kinds (``p.kind in UNIFORM_KINDS``) and other attributes named ``kind`` (``dtype.kind == "f"``, a lobe's
  ``"diffuse"``) are not counted.

Used by ``tests/test_layers.py``, which also feeds it packages broken on purpose.
"""

from __future__ import annotations

import ast
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

#: Sub-packages or modules (first component below the top package) and what they must not import.
FORBIDDEN = {
    "models": {"analysis", "fitting", "export", "mitsuba", "figures", "explorer", "cli", "conversion"},
    "mitsuba": {"fitting", "figures", "explorer", "cli", "conversion"},
    "fitting": {"conversion"},
    "vec": {"bxdf", "registry"},
    "warps": {"bxdf", "registry"},
}
#: Longest function, in lines from ``def`` to its last line.
MAX_LINES = 80
#: Modules allowed to name command-line flags in their errors.
FLAG_OWNERS = {"cli"}
#: The package that owns ``"material:"`` specs (not ``materials``: that name is the function
#: ``plausible.materials``, which a subpackage would replace on import).
MATERIAL_OWNER = "catalogue"

#: The names of the parameter kinds, and the module that alone may branch on them.
PARAM_KINDS = {"scalar", "color", "choice", "lobes", "model"}
KIND_OWNER = "params"

_FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]+")


@dataclass
class Report:
    """What :func:`check` found; empty lists mean the package keeps its floors."""
    cycles: list = field(default_factory=list)      # [sorted module names of one cycle]
    floors: list = field(default_factory=list)      # ["file:line a imports b"]
    long_functions: list = field(default_factory=list)  # ["file:line name (N lines)"]
    flags: list = field(default_factory=list)       # ["file:line --flag"]
    material: list = field(default_factory=list)    # ["file:line"]
    kinds: list = field(default_factory=list)       # ["file:line .kind == 'color'"]

    def ok(self) -> bool:
        return not (self.cycles or self.floors or self.long_functions or self.flags or self.material
                    or self.kinds)

    def text(self) -> str:
        out = [f"import cycles: {len(self.cycles)}"]
        out += [f"  {len(c)} modules: {' '.join(c)}" for c in self.cycles]
        for title, items in (("upward imports", self.floors), (f"functions over {MAX_LINES} lines",
                             self.long_functions), ("CLI flags in library errors", self.flags),
                             ("'material:' outside the catalogue package", self.material),
                             (f"Param kind branches outside {KIND_OWNER}.py", self.kinds)):
            out.append(f"{title}: {len(items)}")
            out += [f"  {x}" for x in items]
        return "\n".join(out)


def modules(root: Path) -> dict[str, Path]:
    """Module name -> file, for the package directory ``root`` (its name is the top package)."""
    out = {}
    for f in sorted(root.rglob("*.py")):
        parts = list(f.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = f
    return out


def _imports(name: str, path: Path, mods: dict) -> list[tuple[str, int]]:
    """(imported module of ``mods``, line) for every import statement in the file."""
    is_pkg = path.name == "__init__.py"
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".")
                base = base[:len(base) - node.level + (1 if is_pkg else 0)]
                pkg = ".".join(base + ([node.module] if node.module else []))
            else:
                pkg = node.module
            targets = [f"{pkg}.{a.name}" if f"{pkg}.{a.name}" in mods else pkg for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in mods:       # "a.b.c" of a module "a.b" with attribute c
                t = t.rpartition(".")[0]
            if t and t != name and (t, node.lineno) not in out:
                out.append((t, node.lineno))
    return out


def graph(root: Path) -> dict[str, list[tuple[str, int]]]:
    """Module -> [(module it imports, line)] inside the package ``root``."""
    mods = modules(root)
    return {m: _imports(m, p, mods) for m, p in mods.items()}


def cycles(g: dict) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):                            # iterative, so deep graphs do not hit the recursion limit
        work = [(v, iter(g.get(v, ())))]
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        while work:
            node, it = work[-1]
            for w, _ in it:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(g.get(w, ()))))
                    break
                if w in on:
                    low[node] = min(low[node], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == node:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))

    for v in g:
        if v not in index:
            visit(v)
    return sorted(out)


def _floor(mod: str) -> str:
    parts = mod.split(".")
    return parts[1] if len(parts) > 1 else ""


def check(root: Path) -> Report:
    """Walk the package directory ``root`` and report what breaks the floors."""
    root = Path(root)
    mods = modules(root)
    g = graph(root)
    rep = Report(cycles=cycles(g))
    for m, edges in g.items():
        bad = FORBIDDEN.get(_floor(m), set())
        for t, line in edges:
            if _floor(t) in bad:
                rep.floors.append(f"{_rel(mods[m], root)}:{line} {m} imports {t}")
    for m, path in mods.items():
        tree = ast.parse(path.read_text(), str(path))
        rel = _rel(path, root)
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_LINES:
                    rep.long_functions.append(f"{rel}:{node.lineno} {node.name} ({n} lines)")
            if isinstance(node, ast.Raise) and node.exc is not None and _floor(m) not in FLAG_OWNERS:
                for s in _strings(node.exc):
                    rep.flags += [f"{rel}:{node.lineno} {f}" for f in _FLAG.findall(s)]
        if _floor(m) not in (MATERIAL_OWNER, "cli"):
            skip = _docstrings(tree) | {n for r in ast.walk(tree) if isinstance(r, ast.Raise) for n in ast.walk(r)}
            for node in ast.walk(tree):
                if (isinstance(node, ast.Constant) and isinstance(node.value, str) and node not in skip
                        and "material:" in node.value):
                    rep.material.append(f"{rel}:{node.lineno}")
        if _floor(m) != KIND_OWNER:
            rep.kinds += [f"{rel}:{line} {text}" for line, text in _kind_branches(tree)]
    return rep


def _kind_branches(tree) -> list[tuple[int, str]]:
    """(line, source) of every comparison of an attribute ``kind`` with a parameter kind's name."""
    out = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Compare):
            continue
        sides = [node.left, *node.comparators]
        if not any(isinstance(s, ast.Attribute) and s.attr == "kind" for s in sides):
            continue
        named = set()
        for s in sides:
            for c in ([s] if isinstance(s, ast.Constant) else
                      s.elts if isinstance(s, (ast.Tuple, ast.List, ast.Set)) else []):
                if isinstance(c, ast.Constant) and isinstance(c.value, str):
                    named.add(c.value)
        if named & PARAM_KINDS:
            out.append((node.lineno, ast.unparse(node)))
    return out


def _strings(node) -> list[str]:
    return [n.value for n in ast.walk(node) if isinstance(n, ast.Constant) and isinstance(n.value, str)]


def _docstrings(tree) -> set:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                out.add(first.value)
    return out


def _rel(path: Path, root: Path) -> str:
    return str(path.relative_to(root.parent))


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    root = Path(argv[0]) if argv else Path(__file__).resolve().parent.parent / "src" / "plausible"
    rep = check(root)
    print(rep.text())
    return 0 if rep.ok() else 1


if __name__ == "__main__":
    sys.exit(main())
