#!/usr/bin/env python3
"""Parses a USD ASCII layer by the .usda grammar (the subset a stage of time-sampled meshes uses: layer
metadata, def/over/class prims with a type and optional metadata, attributes with a type, optional
`uniform`/`custom`, a value or `.timeSamples` dictionary; values are numbers, strings, tokens, tuples and
arrays) and checks every mesh: face counts against indices, indices against points, every time sample with
the same number of finite points. Prints one line per mesh; exits 1 with the line and column of the first
error.

Usage: check_usda.py FILE.usda [EXPECTED_MESHES [EXPECTED_SAMPLES]]
"""
import math
import re
import sys

TOKEN = re.compile(r'''
    (?P<ws>[ \t\r\n]+|\#[^\n]*)
  | (?P<string>"(?:[^"\\\n]|\\.)*")
  | (?P<number>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf\b|nan\b)
  | (?P<ident>[A-Za-z_][A-Za-z0-9_]*(?:\[\])?(?:[:.][A-Za-z_][A-Za-z0-9_]*)*)
  | (?P<punct>[()\[\]{}=,:])
''', re.X)


class ParseError(Exception):
    pass


class Parser:
    def __init__(self, text):
        if not text.startswith('#usda 1.0'):
            raise ParseError('1:1: a USD ASCII layer starts with "#usda 1.0"')
        self.text = text
        self.tokens = []
        pos = len('#usda 1.0')
        while pos < len(text):
            m = TOKEN.match(text, pos)
            if not m:
                raise ParseError(f'{self.where(pos)}: unexpected character {text[pos]!r}')
            if m.lastgroup != 'ws':
                self.tokens.append((m.lastgroup, m.group(), pos))
            pos = m.end()
        self.i = 0

    def where(self, pos):
        line = self.text.count('\n', 0, pos) + 1
        return f'{line}:{pos - (self.text.rfind(chr(10), 0, pos) + 1) + 1}'

    def peek(self):
        return self.tokens[self.i] if self.i < len(self.tokens) else ('eof', '', len(self.text))

    def take(self, kind=None, value=None):
        tok = self.peek()
        if (kind and tok[0] != kind) or (value is not None and tok[1] != value):
            raise ParseError(f'{self.where(tok[2])}: expected {value or kind}, found {tok[1]!r}')
        self.i += 1
        return tok

    def value(self):
        kind, text, _ = self.peek()
        if kind == 'number':
            self.i += 1
            return float(text)
        if kind == 'string':
            self.i += 1
            return text[1:-1]
        if kind == 'ident':
            self.i += 1
            return text
        if text in '([':
            close = ')' if text == '(' else ']'
            self.i += 1
            items = []
            while self.peek()[1] != close:
                items.append(self.value())
                if self.peek()[1] == ',':
                    self.i += 1
                elif self.peek()[1] != close:
                    raise ParseError(f'{self.where(self.peek()[2])}: expected , or {close}')
            self.i += 1
            return tuple(items) if close == ')' else list(items)
        raise ParseError(f'{self.where(self.peek()[2])}: expected a value, found {text!r}')

    def metadata(self):
        """( key = value ... ) or ( "doc string" ... )."""
        self.take('punct', '(')
        out = {}
        while self.peek()[1] != ')':
            if self.peek()[0] == 'string':
                out['doc'] = self.value()
                continue
            key = self.take('ident')[1]
            self.take('punct', '=')
            out[key] = self.value()
        self.take('punct', ')')
        return out

    def samples(self):
        self.take('punct', '{')
        out = {}
        while self.peek()[1] != '}':
            t = float(self.take('number')[1])
            self.take('punct', ':')
            out[t] = self.value()
            if self.peek()[1] == ',':
                self.i += 1
        self.take('punct', '}')
        return out

    def prim(self):
        self.take('ident')  # def / over / class
        type_name = self.take('ident')[1] if self.peek()[0] == 'ident' else ''
        name = self.take('string')[1][1:-1]
        if self.peek()[1] == '(':
            self.metadata()
        self.take('punct', '{')
        prim = {'type': type_name, 'name': name, 'attrs': {}, 'children': []}
        while self.peek()[1] != '}':
            if self.peek()[1] in ('def', 'over', 'class'):
                prim['children'].append(self.prim())
                continue
            qualifiers = []
            while self.peek()[1] in ('uniform', 'custom'):
                qualifiers.append(self.take()[1])
            type_tok = self.take('ident')[1]
            attr = self.take('ident')[1]
            if attr.endswith('.timeSamples'):
                self.take('punct', '=')
                prim['attrs'][attr[:-len('.timeSamples')]] = ('samples', type_tok, self.samples())
            else:
                value = None
                if self.peek()[1] == '=':
                    self.i += 1
                    value = self.value()
                prim['attrs'][attr] = ('value', type_tok, value)
        self.take('punct', '}')
        return prim

    def layer(self):
        meta = self.metadata() if self.peek()[1] == '(' else {}
        prims = []
        while self.peek()[0] != 'eof':
            prims.append(self.prim())
        return meta, prims


def meshes(prims):
    for p in prims:
        if p['type'] == 'Mesh':
            yield p
        yield from meshes(p['children'])


def main():
    path = sys.argv[1]
    with open(path, encoding='utf-8') as f:
        text = f.read()
    try:
        meta, prims = Parser(text).layer()
        if meta.get('defaultPrim') not in [p['name'] for p in prims]:
            raise ParseError(f'defaultPrim {meta.get("defaultPrim")!r} names no root prim')
        found = list(meshes(prims))
        sample_counts = set()
        for m in found:
            a = m['attrs']
            counts, indices = a['faceVertexCounts'][2], a['faceVertexIndices'][2]
            if sum(int(c) for c in counts) != len(indices):
                raise ParseError(f'mesh {m["name"]}: face counts sum to {sum(counts)}, {len(indices)} indices')
            kind, type_name, samples = a['points']
            if kind != 'samples' or type_name != 'point3f[]':
                raise ParseError(f'mesh {m["name"]}: points are not time-sampled point3f[]')
            sizes = {len(v) for v in samples.values()}
            if len(sizes) != 1:
                raise ParseError(f'mesh {m["name"]}: time samples of different sizes {sorted(sizes)}')
            n = sizes.pop()
            if any(not (0 <= int(i) < n) for i in indices):
                raise ParseError(f'mesh {m["name"]}: a face index is outside its {n} points')
            if any(len(p) != 3 or not all(math.isfinite(c) for c in p) for v in samples.values() for p in v):
                raise ParseError(f'mesh {m["name"]}: a point is not 3 finite numbers')
            times = sorted(samples)
            if times[0] < meta.get('startTimeCode', 0) or times[-1] > meta.get('endTimeCode', times[-1]):
                raise ParseError(f'mesh {m["name"]}: samples outside the stage\'s time codes')
            sample_counts.add(len(times))
            print(f'{m["name"]}: {len(counts)} faces, {n} points, {len(times)} time samples')
        if len(sys.argv) > 2 and len(found) != int(sys.argv[2]):
            raise ParseError(f'{len(found)} meshes, expected {sys.argv[2]}')
        if len(sys.argv) > 3 and sample_counts != {int(sys.argv[3])}:
            raise ParseError(f'time samples per mesh {sorted(sample_counts)}, expected {sys.argv[3]}')
    except (ParseError, KeyError, ValueError, TypeError) as e:
        print(f'{path}: {e}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
