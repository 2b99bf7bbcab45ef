#!/usr/bin/env python3
"""Parses a USD ASCII layer by the .usda grammar (the subset a stage of time-sampled meshes uses: layer
metadata, def/over/class prims with a type and optional metadata, attributes with a type, optional
`uniform`/`custom`, a value or `.timeSamples` dictionary; values are numbers, strings, tokens, tuples and
arrays, with metadata on prims and attributes) and checks every mesh: face counts against indices, indices
against points, every time sample with the same number of finite points; where present, an extent per sample
that bounds its points, unit normals per vertex and sample, and texture coordinates `primvars:st` per vertex
(both with interpolation "vertex"). Prints one line per mesh; exits 1 with the line and column of the first
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
                if attr not in prim['attrs'] or value is not None:
                    prim['attrs'][attr] = ('value', type_tok, value)
            if self.peek()[1] == '(':
                prim.setdefault('attr_meta', {}).setdefault(attr.replace('.timeSamples', ''), {}).update(self.metadata())
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
        if meta.get('upAxis') not in ('Y', 'Z'):
            raise ParseError(f'upAxis {meta.get("upAxis")!r} is not "Y" or "Z"')
        unit = meta.get('metersPerUnit', 0.01)  # USD's fallback: centimetres
        if not (isinstance(unit, (int, float)) and unit > 0 and math.isfinite(unit)):
            raise ParseError(f'metersPerUnit {unit!r} is not a positive number')
        print(f'stage: metersPerUnit {unit:g}, upAxis {meta["upAxis"]}')
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
            if 'extent' in a:
                kind, type_name, boxes = a['extent']
                if kind != 'samples' or type_name != 'float3[]' or sorted(boxes) != times:
                    raise ParseError(f'mesh {m["name"]}: extent is not a float3[] sample per points sample')
                for t in times:
                    lo, hi = boxes[t]
                    if any(not (lo[d] - 1e-6 * (1 + abs(lo[d])) <= p[d] <= hi[d] + 1e-6 * (1 + abs(hi[d])))
                           for p in samples[t] for d in range(3)):
                        raise ParseError(f'mesh {m["name"]}: a point at time {t:g} lies outside its extent')
            interpolation = lambda name: m.get('attr_meta', {}).get(name, {}).get('interpolation')
            if 'normals' in a:
                kind, type_name, normals = a['normals']
                if kind != 'samples' or type_name != 'normal3f[]' or sorted(normals) != times:
                    raise ParseError(f'mesh {m["name"]}: normals are not a normal3f[] sample per points sample')
                if interpolation('normals') != 'vertex':
                    raise ParseError(f'mesh {m["name"]}: normals without interpolation "vertex"')
                for t in times:
                    if len(normals[t]) != n or any(len(v) != 3 or not (abs(math.hypot(*v) - 1) < 1e-5 or math.hypot(*v) == 0)
                                                   for v in normals[t]):
                        raise ParseError(f'mesh {m["name"]}: the normals at time {t:g} are not {n} unit vectors')
            if 'primvars:st' in a:
                kind, type_name, st = a['primvars:st']
                if kind != 'value' or type_name != 'texCoord2f[]' or len(st) != n or interpolation('primvars:st') != 'vertex':
                    raise ParseError(f'mesh {m["name"]}: primvars:st is not {n} texCoord2f with interpolation "vertex"')
                if any(len(v) != 2 or not all(math.isfinite(c) for c in v) for v in st):
                    raise ParseError(f'mesh {m["name"]}: a texture coordinate is not 2 finite numbers')
            sample_counts.add(len(times))
            extras = [name for name in ('extent', 'normals', 'primvars:st') if name in a]
            print(f'{m["name"]}: {len(counts)} faces, {n} points, {len(times)} time samples' +
                  (f' ({", ".join(extras)})' if extras else ''))
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
