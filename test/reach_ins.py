"""Reach-ins of one layer into the data components of another layer's types,
found by following reference chains through the declared types (used by
test/layers.py; `python3 test/reach_ins.py` lists them).

A chain `a(i)%b%c` is resolved from left to right: `a`'s type comes from its
declaration in the file (`type(T)` or `class(T)`), from an `associate`
name (the type of the chain it stands for) or from a `select type` name in a
`type is` / `class is` branch; each next name is a component of the type
reached so far (its parents' included), whose declared type continues the
chain. A step into a data component of a type defined in an inner folder
(not a type-bound procedure) is a reach-in. Chains through function results
and pointer remapping are not followed; declarations are taken as they come
in order (a name has the type of its latest declaration, which in a
procedure is its own).
"""
import os
import re

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')

TYPE_START = re.compile(r'type\s*(?:,\s*([^:]*))?::\s*(\w+)\s*$', re.I)
EXTENDS = re.compile(r'extends\s*\(\s*(\w+)\s*\)', re.I)
DECLARED = re.compile(r'^(?:type|class)\s*\(\s*(\w+|\*)\s*\)([^:]*)::\s*(.*)$', re.I)
OTHER_DECL = re.compile(r'^(?:real|integer|logical|character|complex|procedure)\b[^:]*::\s*(.*)$',
                        re.I)
SELECT = re.compile(r'^(?:\w+\s*:\s*)?select\s+type\s*\(\s*(\w+)\s*=>', re.I)
SELECT_PLAIN = re.compile(r'^(?:\w+\s*:\s*)?select\s+type\s*\(\s*(\w+)\s*\)', re.I)
BRANCH = re.compile(r'^(?:type|class)\s+is\s*\(\s*(\w+)\s*\)', re.I)
ASSOCIATE = re.compile(r'^(?:\w+\s*:\s*)?associate\s*\((.*)\)\s*$', re.I)


def sources(*folders):
    """(path relative to the checkout, path) of the Fortran sources below `folders`."""
    for folder in folders:
        for base, _, files in os.walk(os.path.join(ROOT, folder)):
            for f in sorted(files):
                if f.endswith(('.f90', '.F90', '.inc')):
                    path = os.path.join(base, f)
                    yield os.path.relpath(path, ROOT), path


def _statements(path):
    """(line number, code) of a file's statements: comments dropped,
    continuation lines joined, strings blanked."""
    out, pending, first = [], '', 0
    for k, line in enumerate(open(path, encoding='utf-8'), 1):
        code = _strip(line).strip()
        if pending:
            code = code[1:].strip() if code.startswith('&') else code
        else:
            first = k
        if code.endswith('&'):
            pending += code[:-1] + ' '
            continue
        out.append((first, pending + code))
        pending = ''
    return out


def _strip(line):
    """The line without its comment, its character literals blanked."""
    out, quote = [], None
    for ch in line:
        if quote:
            out.append(' ' if ch != quote else ch)
            if ch == quote:
                quote = None
        elif ch in '\'"':
            quote = ch
            out.append(ch)
        elif ch == '!':
            break
        else:
            out.append(ch)
    return ''.join(out).rstrip('\n')


def _split_top(text, sep=','):
    """`text` split at `sep` outside parentheses."""
    parts, depth, cur = [], 0, ''
    for ch in text:
        if ch == '(':
            depth += 1
        elif ch == ')':
            depth -= 1
        if ch == sep and depth == 0:
            parts.append(cur)
            cur = ''
        else:
            cur += ch
    parts.append(cur)
    return parts


class Type:
    def __init__(self, name, folder, parent):
        self.name, self.folder, self.parent = name, folder, parent
        self.data = {}        # component -> declared type name (or None)
        self.bindings = set()


def derived_types(folders=('src',)):
    """{name: Type} of the derived types defined below `folders`."""
    types = {}
    for rel, path in sources(*folders):
        folder = rel.split(os.sep)[1] if rel.startswith('src') else rel
        current, bound = None, False
        for _, code in _statements(path):
            m = TYPE_START.match(code)
            if m and not re.match(r'type\s+is\b', code, re.I):
                attrs = m.group(1) or ''
                parent = EXTENDS.search(attrs)
                current = Type(m.group(2).lower(), folder,
                               parent.group(1).lower() if parent else None)
                types[current.name], bound = current, False
                continue
            if current is None:
                continue
            if re.match(r'end\s*type\b', code, re.I):
                current = None
            elif code.lower() == 'contains':
                bound = True
            elif '::' in code:
                names = [re.match(r'\s*(\w+)', p) for p in _split_top(code.split('::', 1)[1])]
                names = [n.group(1).lower() for n in names if n]
                if bound:
                    current.bindings.update(names)
                    continue
                d = DECLARED.match(code)
                kind = d.group(1).lower() if d else None
                for n in names:
                    current.data[n] = kind
    return types


def _component(types, tname, name):
    """(owner type, declared type) of component `name` of type `tname`,
    looking in its parents; (None, None) if it is not a data component."""
    while tname in types:
        t = types[tname]
        if name in t.bindings:
            return None, None
        if name in t.data:
            return t, t.data[name]
        tname = t.parent
    return None, None


def _chains(code):
    """(base, [names]) of every `base(...)%name(...)%...` chain in `code`."""
    out, i, n = [], 0, len(code)
    while i < n:
        m = re.compile(r'[A-Za-z]\w*').match(code, i)
        if not m or (i > 0 and (code[i - 1].isalnum() or code[i - 1] == '_')):
            i += 1
            continue
        prev = code[:i].rstrip()
        base, j, names = m.group(0).lower(), m.end(), []
        if prev.endswith('%'):
            i = j
            continue
        while True:
            k = j
            while k < n and code[k] == ' ':
                k += 1
            if k < n and code[k] == '(':
                depth = 0
                while k < n:
                    depth += {'(': 1, ')': -1}.get(code[k], 0)
                    k += 1
                    if depth == 0:
                        break
                while k < n and code[k] == ' ':
                    k += 1
            if k < n and code[k] == '%':
                k += 1
                while k < n and code[k] == ' ':
                    k += 1
                mm = re.compile(r'[A-Za-z]\w*').match(code, k)
                if not mm:
                    break
                names.append(mm.group(0).lower())
                j = mm.end()
            else:
                break
        if names:
            out.append((base, names))
        i = m.end()
    return out


def _resolve(types, kinds, base, names, inner, hits=None):
    """The type a chain reaches (None if unknown); the steps into data
    components of `inner` folders' types are appended to `hits`."""
    tname = kinds.get(base)
    for name in names:
        if tname is None:
            return None
        owner, declared = _component(types, tname, name)
        if owner is None:
            return None
        if hits is not None and owner.folder in inner:
            hits.append('%s%%%s' % (owner.name, name))
        tname = declared
    return tname


def reach_ins(outer=('src/run', 'src/io'), inner=('mbs', 'fe')):
    """['file:line type%component', ...] of the reach-ins of the `outer`
    folders' files into the data components of the `inner` folders' types."""
    types = derived_types()
    found = []
    for rel, path in sources(*outer):
        statements = _statements(path)
        kinds = {}
        selector = None
        for line, code in statements:
            d = DECLARED.match(code)
            if d and d.group(1) != '*':
                # declarations come first in their scope: a name takes the
                # type of its latest declaration
                for part in _split_top(d.group(3)):
                    nm = re.match(r'\s*(\w+)', part)
                    if nm:
                        kinds[nm.group(1).lower()] = d.group(1).lower()
            m = SELECT.match(code) or SELECT_PLAIN.match(code)
            if m:
                selector = m.group(1).lower()
            b = BRANCH.match(code)
            if b and selector:
                kinds[selector] = b.group(1).lower()
            a = ASSOCIATE.match(code)
            if a:
                for part in _split_top(a.group(1)):
                    if '=>' not in part:
                        continue
                    alias, expr = part.split('=>', 1)
                    chains = _chains(expr.strip())
                    expr_base = re.match(r'\s*(\w+)\s*$', expr)
                    if chains and chains[0][1]:
                        kinds[alias.strip().lower()] = _resolve(types, kinds, *chains[0], inner)
                    elif expr_base and expr_base.group(1).lower() in kinds:
                        kinds[alias.strip().lower()] = kinds[expr_base.group(1).lower()]
            if DECLARED.match(code) or OTHER_DECL.match(code):
                continue
            for base, names in _chains(code):
                hits = []
                _resolve(types, kinds, base, names, inner, hits)
                found.extend('%s:%d %s' % (rel, line, h) for h in hits)
    return found


if __name__ == '__main__':
    for r in reach_ins():
        print(r)
