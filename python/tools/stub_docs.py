"""Copies the native module's docstrings into its type stubs.

The Rust doc comments of ``python/src`` are the one source of the Python API's
documentation; PyO3 hands them to the module as ``__doc__``. Editors read the
``.pyi`` stubs instead, so this script writes the same texts into
``python/fitup/_fitup.pyi`` (every module function, class and member the stubs
declare). Run it after changing a doc comment, with the package installed::

    python python/tools/stub_docs.py

``python/tests/test_module.py`` fails while a stub's docstring differs from the
module's.
"""

import ast
import inspect
import sys
from pathlib import Path

STUBS = Path(__file__).resolve().parents[1] / "fitup" / "_fitup.pyi"


def native_doc(native, cls, name):
    """The native docstring of ``cls.name`` (``cls`` None: a module function;
    ``name`` None: the class itself), cleaned as ``inspect.cleandoc`` does."""
    if cls is None:
        obj = getattr(native, name)
    elif name is None:
        obj = getattr(native, cls)
    else:
        obj = getattr(native, cls).__dict__[name]
        # A static or class method's own ``__doc__`` is its wrapper type's.
        obj = getattr(obj, "__func__", obj)
    doc = getattr(obj, "__doc__", None)
    return inspect.cleandoc(doc) if doc else None


def docstring_lines(doc, indent):
    """``doc`` as the lines of a triple-quoted docstring at ``indent``."""
    pad = " " * indent
    prefix = "r" if "\\" in doc else ""
    lines = doc.splitlines()
    if len(lines) == 1:
        return [f'{pad}{prefix}"""{lines[0]}"""']
    out = [f'{pad}{prefix}"""{lines[0]}']
    out += [f"{pad}{line}".rstrip() for line in lines[1:]]
    out.append(f'{pad}"""')
    return out


def edits(tree, native):
    """(first line, last line, new lines) for every stub item, 1-based, inclusive."""
    out = []

    def visit(node, cls):
        if isinstance(node, ast.ClassDef):
            doc = native_doc(native, node.name, None)
        elif node.name.startswith("_"):
            return  # dunders: the class's docstring covers them
        else:
            doc = native_doc(native, cls, node.name)
        if doc is None:
            return
        indent = node.col_offset + 4
        first = node.body[0]
        has_doc = (
            isinstance(first, ast.Expr)
            and isinstance(first.value, ast.Constant)
            and isinstance(first.value.value, str)
        )
        new = docstring_lines(doc, indent)
        if has_doc:
            out.append((first.lineno, first.end_lineno, new, None))
        elif isinstance(first, ast.Expr) and first.value.value is Ellipsis:
            # `def f(...) -> T: ...` on its last line: the docstring replaces `...`.
            out.append((first.lineno, first.end_lineno, new, first.col_offset))

    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            visit(node, None)
        elif isinstance(node, ast.ClassDef):
            visit(node, node.name)
            for member in node.body:
                if isinstance(member, ast.FunctionDef):
                    visit(member, node.name)
    return out


def main():
    import fitup._fitup as native

    text = STUBS.read_text()
    lines = text.splitlines()
    for first, last, new, col in sorted(edits(ast.parse(text), native), reverse=True):
        if col is None:
            lines[first - 1 : last] = new
        else:
            head = lines[first - 1][:col].rstrip()
            lines[first - 1 : last] = [head] + new
    STUBS.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
