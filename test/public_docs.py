#!/usr/bin/env python3
"""Every public procedure, generic interface and derived type of the library
is documented (run by `make test`).

The modules of src/ and legacy/src/ (*.f90, *.F90; the .inc bodies an .F90
includes are read in its place, through a small preprocessor that follows
#define, #undef, #ifdef, #ifndef, #else and #endif, so that a procedure of an
.inc belongs to the including module, under its macro-expanded name, and is
reported at its line in the .inc).

Public: a module with a bare `private` statement exports what a `public`
statement names or what carries the `public` attribute (`type, public ::`);
a module without one exports everything it defines. The external procedures
of legacy/src/ (the classic faces, outside any module) are public too.
Counted: module procedures, the bodies of abstract and of unnamed interface
blocks (external and bind(C) procedures), named generic interfaces (also
operator(...) and assignment(=)) and derived types; internal procedures,
type-bound bindings and the specifics of a generic are not counted unless
they are public themselves.

Documented: a `!>` line directly above the first line of the declaration
(`subroutine`, `function` with any prefixes, `type`, `interface`, `module`),
or FORD's `!!` line directly below its last line. Every module needs its own
`!>` block too.

Prints `pass public-docs/...` or `FAIL public-docs/...: why` lines (one check
per source folder, naming each undocumented item as file:line:name; two
checks of the parser itself: every name of a `public` statement is found
defined, declared or imported, and every unit's end pairs with its start;
the total) and `N passed, M failed` last; exits non-zero on failures.
"""
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
FOLDERS = ('src', 'legacy/src')
SHOWN = int(os.environ.get("PUBLIC_DOCS_SHOWN", "20"))

passed = failed = 0


def report(name, problems, note=''):
    global passed, failed
    if problems:
        failed += 1
        print('FAIL public-docs/%s: %s' % (name, '; '.join(problems[:SHOWN]) +
                                           (' (+%d more)' % (len(problems) - SHOWN)
                                            if len(problems) > SHOWN else '')))
    else:
        passed += 1
        print('pass public-docs/%s%s' % (name, ': ' + note if note else ''))


# ---------------------------------------------------------------- preprocessor

IDENT = re.compile(r'[A-Za-z_]\w*')


def unquoted(text):
    """(index, character) of the characters of a line outside its character
    literals (a doubled quote closes and reopens one: the same positions)."""
    quote = None
    for i, c in enumerate(text):
        if quote:
            if c == quote:
                quote = None
        elif c in '\'"':
            quote = c
        else:
            yield i, c


def code_part(text):
    """The text of a free-form line before its comment (strings respected)."""
    for i, c in unquoted(text):
        if c == '!':
            return text[:i]
    return text


def substitute(text, macros):
    """Object-like macros replaced in the code part of a line (comments kept)."""
    if not macros:
        return text
    code = code_part(text)
    rest = text[len(code):]
    return IDENT.sub(lambda m: macros.get(m.group(0), m.group(0)), code) + rest


def preprocess(path, macros=None, depth=0):
    """The lines of a source file as the compiler sees them: a list of
    (text, file, line number); #include "x" is read from the file's folder,
    inactive #ifdef branches and directives are left out."""
    macros = {} if macros is None else macros
    out, active = [], [True]
    rel = os.path.relpath(path, ROOT)
    with open(path, encoding='utf-8') as f:
        lines = f.read().split('\n')
    for k, text in enumerate(lines, 1):
        d = re.match(r'\s*#\s*(\w+)\s*(.*)$', text)
        if d:
            word, arg = d.group(1), d.group(2).strip()
            on = all(active)
            if word in ('ifdef', 'ifndef'):
                name = arg.split()[0] if arg else ''
                active.append((name in macros) == (word == 'ifdef'))
            elif word == 'else':
                active[-1] = not active[-1]
            elif word == 'endif':
                if len(active) > 1:
                    active.pop()
            elif not on:
                pass
            elif word == 'define':
                parts = arg.split(None, 1)
                if parts:
                    macros[parts[0]] = parts[1].strip() if len(parts) > 1 else ''
            elif word == 'undef':
                macros.pop(arg.split()[0] if arg else '', None)
            elif word == 'include':
                m = re.match(r'"([^"]+)"', arg)
                if m and depth < 8:
                    inc = os.path.join(os.path.dirname(path), m.group(1))
                    if os.path.exists(inc):
                        out.extend(preprocess(inc, macros, depth + 1))
            continue
        if all(active):
            out.append((substitute(text, macros), rel, k))
    return out


# ---------------------------------------------------------------- statements

def statements(lines):
    """Logical statements: (code text in lower case, index of the first and of
    the last physical line), continuation lines joined, comments dropped,
    `;`-separated statements split."""
    out, buf, first = [], '', None
    for i, (text, _, _) in enumerate(lines):
        code = code_part(text).strip()
        if not code:
            continue          # comment or blank lines inside a continuation
        if buf:
            if code.startswith('&'):
                code = code[1:].lstrip()
        else:
            first = i
        if code.endswith('&'):
            buf += code[:-1] + ' '
            continue
        buf += code
        for part in split_semicolons(buf):
            if part.strip():
                out.append((part.strip().lower(), first, i))
        buf = ''
    return out


def split_semicolons(code):
    parts, start = [], 0
    for i, c in unquoted(code):
        if c == ';':
            parts.append(code[start:i])
            start = i + 1
    parts.append(code[start:])
    return parts


def names_of(text):
    """The entity names of an access or declaration list: `a, b => c,
    operator(+), assignment(=), x(3) = 1` gives a, b, operator(+), ..."""
    names, depth, item = [], 0, ''
    for c in text + ',':
        if c == ',' and depth == 0:
            item = item.strip()
            m = re.match(r'(operator\s*\([^)]*\)|assignment\s*\(\s*=\s*\)|\w+)', item)
            if m:
                names.append(re.sub(r'\s+', '', m.group(1)))
            item = ''
            continue
        if c in '([':
            depth += 1
        elif c in ')]':
            depth -= 1
        item += c
    return names


PAREN = r'\((?:[^()]|\([^()]*\))*\)'
PREFIX = (r'(?:(?:pure|impure|elemental|recursive|non_recursive|module)\s+'
          r'|(?:integer|real|logical|complex|character|double\s+precision|type|class)\s*'
          r'(?:' + PAREN + r')?\s*(?:\*\s*\d+\s*)?)*')
PROCEDURE = re.compile(r'^' + PREFIX + r'(subroutine|function)\s+(\w+)')
# the body of a separate module procedure (a submodule's `module procedure name`)
SEPARATE = re.compile(r'^module\s+(procedure)\s+(\w+)$')
TYPE_DEF = re.compile(r'^type\s*(?:,(.*?))?(?:::)?\s*(\w+)\s*(?:\([\w\s,]*\))?$')
INTERFACE = re.compile(r'^(abstract\s+)?interface\b\s*(.*)$')
MODULE = re.compile(r'^module\s+(\w+)$')
# `end`, `end subroutine name`, `endfunction`, ...; not `end if`, `end do`, ...
END = re.compile(r'^end(?:\s*(subroutine|function|module|submodule|type|interface|program|'
                 r'procedure|block\s*data)\b.*)?$')
UNIT_ENDS = ('subroutine', 'function', 'module', 'submodule', 'type', 'interface',
             'program', 'procedure', 'blockdata', 'block data', None)
DECLARATION = re.compile(r'^(integer|real|logical|complex|character|double\s+precision|'
                         r'type\s*\(|class\s*\(|procedure\s*\(|enumerator)')


class Module:
    def __init__(self, name, where, doc):
        self.name, self.where, self.doc = name, where, doc
        self.default_private = False
        self.public, self.private, self.declared, self.imported = set(), set(), set(), set()
        self.use_all = False
        self.items = []   # (name, kind, where, documented, public attribute)


def documented(lines, first, last):
    above = lines[first - 1][0].lstrip() if first > 0 else ''
    below = lines[last + 1][0].lstrip() if last + 1 < len(lines) else ''
    return above.startswith('!>') or below.startswith('!!')


unbalanced = []   # files whose units this parser could not pair up


def scan(path):
    """The modules of one source file, and its external procedures."""
    lines = preprocess(path)
    modules, externals = [], []
    stack = []            # ('module'|'procedure'|'type'|'interface', ...)
    module = None
    for code, first, last in statements(lines):
        where = '%s:%d' % (lines[first][1], lines[first][2])
        doc = documented(lines, first, last)
        top = stack[-1][0] if stack else None
        m = END.match(code)
        if m and m.group(1) in UNIT_ENDS:
            if not stack:
                unbalanced.append('%s: an end without a unit' % where)
            elif stack.pop()[0] == 'module':
                module = None
            continue
        if top == 'type':
            continue      # components and bindings
        if top == 'interface':
            p = PROCEDURE.match(code)
            if p:
                generic = stack[-1][1]
                if module is not None and generic in (None, 'abstract'):
                    kind = 'abstract interface' if generic else 'interface body'
                    module.items.append((p.group(2), kind, where, doc, False))
                stack.append(('procedure', p.group(2)))
            continue
        if top == 'procedure':
            p = PROCEDURE.match(code) or SEPARATE.match(code)
            if p:
                stack.append(('procedure', p.group(2)))      # internal procedure
            elif re.match(r'^(abstract\s+)?interface\b', code):
                stack.append(('interface', 'local'))
            elif TYPE_DEF.match(code) and not re.match(r'^type\s*(\(|is\b)', code):
                stack.append(('type', None))
            continue
        # module level, or outside any module
        mm = MODULE.match(code)
        if mm and mm.group(1) != 'procedure':
            module = Module(mm.group(1), where, doc)
            modules.append(module)
            stack.append(('module', module))
            continue
        if re.match(r'^(program|submodule|block\s*data)\b', code):
            stack.append(('procedure', None))
            continue
        p = PROCEDURE.match(code) or SEPARATE.match(code)
        if p:
            if module is not None:
                module.items.append((p.group(2), 'procedure', where, doc, False))
            else:
                externals.append((p.group(2), 'external procedure', where, doc, True))
            stack.append(('procedure', p.group(2)))
            continue
        i = INTERFACE.match(code)
        if i:
            spec = re.sub(r'\s+', '', i.group(2))
            if i.group(1) or not spec:
                stack.append(('interface', 'abstract' if i.group(1) else None))
            else:
                if module is not None:
                    module.items.append((spec, 'generic interface', where, doc, False))
                stack.append(('interface', spec))
            continue
        t = TYPE_DEF.match(code)
        if t and not re.match(r'^type\s*(\(|is\b)', code):
            attrs = (t.group(1) or '').replace(' ', '')
            if module is not None:
                module.items.append((t.group(2), 'type', where, doc,
                                     bool(re.search(r'(^|,)public(,|$)', attrs))))
                module.declared.add(t.group(2))
            stack.append(('type', t.group(2)))
            continue
        if module is None:
            continue
        if code == 'private':
            module.default_private = True
        elif code == 'public':
            module.default_private = False
        elif re.match(r'^public\b\s*(::)?', code):
            module.public.update(names_of(re.sub(r'^public\s*(::)?', '', code)))
        elif re.match(r'^private\b\s*(::)?', code):
            module.private.update(names_of(re.sub(r'^private\s*(::)?', '', code)))
        elif code.startswith('use'):
            u = re.match(r'^use\b(?:\s*,\s*\w+\s*::)?\s*:*\s*(\w+)\s*(,\s*only\s*:(.*))?$', code)
            if u and u.group(2):
                for item in names_of(u.group(3)):
                    module.imported.add(item)
                for local in re.findall(r'(\w+)\s*=>', u.group(3)):
                    module.imported.add(local)
            elif u:
                module.use_all = True
        elif DECLARATION.match(code) and '::' in code:
            head, _, rest = code.partition('::')
            public = bool(re.search(r',\s*public\b', head))
            for name in names_of(rest):
                module.declared.add(name)
                if public:
                    module.public.add(name)
    if stack:
        unbalanced.append('%s: %d units not closed at the end' % (lines[-1][1], len(stack)))
    return modules, externals


# ---------------------------------------------------------------- the checks

def sources(folder):
    for base, _, files in sorted(os.walk(os.path.join(ROOT, folder))):
        for f in sorted(files):
            if f.endswith(('.f90', '.F90')):
                yield os.path.join(base, f)


def public_items(module):
    """The module's items that it exports, and the names its `public`
    statements give that it neither defines, declares nor imports."""
    defined = {name for name, _, _, _, _ in module.items}
    out = []
    for name, kind, where, doc, attribute in module.items:
        if name in module.private:
            continue
        if attribute or name in module.public or not module.default_private:
            out.append((name, kind, where, doc))
    unknown = sorted(n for n in module.public
                     if n not in defined and n not in module.declared
                     and n not in module.imported and not module.use_all)
    return out, unknown


total = documented_count = 0
all_modules = 0
unknown_names = []
for folder in [os.path.join(f, d) for f in FOLDERS
               for d in sorted(os.listdir(os.path.join(ROOT, f)))
               if os.path.isdir(os.path.join(ROOT, f, d))] + list(FOLDERS):
    # src/<area> and legacy/src/<face>; then the files directly in src/ and legacy/src/
    top_only = folder in FOLDERS
    paths = [p for p in sources(folder)
             if not top_only or os.path.dirname(p) == os.path.join(ROOT, folder)]
    if not paths:
        continue
    missing, count, nmodules = [], 0, 0
    for path in paths:
        modules, externals = scan(path)
        nmodules += len(modules)
        for module in modules:
            count += 1
            if not module.doc:
                missing.append('%s:module %s' % (module.where, module.name))
            items, unknown = public_items(module)
            unknown_names.extend('%s: %s' % (module.name, n) for n in unknown)
            seen = set()
            for name, kind, where, doc in items:
                # an .inc's type or procedure read twice is one item
                if (where, name) in seen:
                    continue
                seen.add((where, name))
                count += 1
                if not doc:
                    missing.append('%s:%s (%s)' % (where, name, kind))
        for name, kind, where, doc, _ in externals:
            count += 1
            if not doc:
                missing.append('%s:%s (%s)' % (where, name, kind))
    total += count
    documented_count += count - len(missing)
    all_modules += nmodules
    report(folder + ('/ (top level)' if top_only else ''), missing,
           '%d module%s and %d public procedures, interfaces and types documented'
           % (nmodules, '' if nmodules == 1 else 's', count - nmodules))

# A public name that the scan did not find defined, declared or imported is
# a declaration this parser does not understand.
report('parser-finds-every-public-name', unknown_names)
report('parser-pairs-every-end', unbalanced)
report('total', [] if documented_count == total else
       ['%d of %d public items undocumented' % (total - documented_count, total)],
       '%d public procedures, interfaces and types and %d modules documented'
       % (total - all_modules, all_modules))

print('%d passed, %d failed' % (passed, failed))
sys.exit(1 if failed else 0)
