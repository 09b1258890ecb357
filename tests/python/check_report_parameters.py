#!/usr/bin/python3
"""Independent check that karst report shows every scenario parameter in full.

Reads the "parameters" object of ENSEMBLE_DIR/ensemble.json with Python's own
json module, reads back the nested table the report renders inside its
<details> block with Python's html.parser, and compares the two value by
value: objects are tables keyed by member name, arrays of scalars are inline
"[a, b, "c"]" lists, an array of objects that all have the same member names is ONE
table (class "rows": a header row of names in the first element's order, then one
row per element), other arrays are tables with rows "[0]", "[1]", ...,
numbers are the literals of the file (compared as floats), strings in full.
Nothing is skipped or truncated, and each array must be rendered in the form its
elements call for, or the check fails.

Usage: check_report_parameters.py REPORT.html ENSEMBLE_DIR   (exit 0 when equal)
"""
import json
import os
import sys
from html.parser import HTMLParser


class Node:
    def __init__(self, tag, attrs=()):
        self.tag, self.children, self.text = tag, [], ""
        self.classes = (dict(attrs).get("class") or "").split()


class TreeBuilder(HTMLParser):
    """The element tree of the <details> block (tables, rows, cells, text)."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.root, self.stack, self.inside = None, [], 0

    def handle_starttag(self, tag, attrs):
        if tag == "details" and self.root is None:
            self.root = Node(tag)
            self.stack = [self.root]
            return
        if self.stack:
            n = Node(tag, attrs)
            self.stack[-1].children.append(n)
            self.stack.append(n)

    def handle_endtag(self, tag):
        if not self.stack:
            return
        while self.stack and self.stack[-1].tag != tag:
            self.stack.pop()
        if self.stack:
            self.stack.pop()

    def handle_data(self, data):
        if self.stack:
            self.stack[-1].text += data


def text_of(n):
    return n.text + "".join(text_of(c) for c in n.children)


def table_to_value(t):
    rows = [r for r in t.children if r.tag == "tr"]
    if "rows" in t.classes:
        return rows_table_to_value(rows)
    keys, values = [], []
    for r in rows:
        th = [c for c in r.children if c.tag == "th"]
        td = [c for c in r.children if c.tag == "td"]
        if len(th) != 1 or len(td) != 1:
            return ("bad", "a row of %d <th> and %d <td> in a name/value table" % (len(th), len(td)))
        keys.append(text_of(th[0]))
        values.append(cell_to_value(td[0]))
    if keys and all(k == "[%d]" % i for i, k in enumerate(keys)):
        return ("array", values)
    return ("object", list(zip(keys, values)))


def rows_table_to_value(rows):
    """One table for an array of same-keyed objects: header of names, one row per element.
    Each element becomes ("row", [(name, value), ...]); the array ("rows", elements)."""
    if not rows:
        return ("bad", "a rows table without a header row")
    header = [text_of(c) for c in rows[0].children if c.tag == "th"]
    if [c for c in rows[0].children if c.tag != "th"]:
        return ("bad", "a header row with a cell that is not <th>")
    elements = []
    for r in rows[1:]:
        if [c for c in r.children if c.tag != "td"]:
            return ("bad", "a data row with a cell that is not <td>")
        cells = [cell_to_value(c) for c in r.children if c.tag == "td"]
        if len(cells) != len(header):
            return ("bad", "a row of %d cells under %d names" % (len(cells), len(header)))
        elements.append(("row", list(zip(header, cells))))
    return ("rows", elements)


def same_keyed(objects):
    """Whether the report must show this array as one table (the rule of src/report/report.c:
    a non-empty array of objects with the same non-empty set of member names)."""
    if not objects or not all(isinstance(o, dict) for o in objects) or not objects[0]:
        return False
    return all(set(o) == set(objects[0]) for o in objects)


def cell_to_value(td):
    tables = [c for c in td.children if c.tag == "table"]
    if tables:
        return table_to_value(tables[0])
    return ("text", td.text)


def same(expected, got, where):
    kind = got[0]
    if isinstance(expected, dict):
        if kind == "row":
            # A row of a rows table: the columns follow the first element's order.
            names = [k for k, _ in got[1]]
            if sorted(names) != sorted(expected) or len(set(names)) != len(names):
                return fail(where, sorted(expected), names)
            return all(same(expected[k], v, where + "." + k) for k, v in got[1])
        if not expected:
            return kind == "text" and got[1] == "{ }" or fail(where, "{ }", got)
        if kind != "object":
            return fail(where, "an object", got)
        if [k for k, _ in got[1]] != list(expected):
            return fail(where, list(expected), [k for k, _ in got[1]])
        return all(same(expected[k], v, where + "." + k) for k, v in got[1])
    if isinstance(expected, list):
        if not expected:
            return kind == "text" and got[1] == "[ ]" or fail(where, "[ ]", got)
        if all(not isinstance(e, (dict, list)) for e in expected):
            if kind != "text":
                return fail(where, "an inline list", got)
            return scalars_equal(expected, json.loads(got[1])) or fail(where, expected, got)
        if same_keyed(expected):
            if kind != "rows" or len(got[1]) != len(expected):
                return fail(where, "one table of %d rows" % len(expected), got)
            if [k for k, _ in got[1][0][1]] != list(expected[0]):
                return fail(where, "columns %r" % list(expected[0]), [k for k, _ in got[1][0][1]])
            return all(same(e, g, "%s[%d]" % (where, i))
                       for i, (e, g) in enumerate(zip(expected, got[1])))
        if kind != "array" or len(got[1]) != len(expected):
            return fail(where, "an array of %d" % len(expected), got)
        return all(same(e, g, "%s[%d]" % (where, i)) for i, (e, g) in enumerate(zip(expected, got[1])))
    if kind != "text":
        return fail(where, expected, got)
    if isinstance(expected, str):
        return got[1] == expected or fail(where, expected, got)
    if expected is None or isinstance(expected, bool):
        return got[1] == json.dumps(expected) or fail(where, json.dumps(expected), got)
    return scalars_equal([expected], [float(got[1])]) or fail(where, expected, got)


def scalars_equal(a, b):
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if isinstance(x, bool) or x is None or isinstance(x, str):
            if x != y or type(x) != type(y):
                return False
        elif not (isinstance(y, (int, float)) and not isinstance(y, bool) and float(x) == float(y)):
            return False
    return True


def fail(where, expected, got):
    print("parameters%s: expected %r, report shows %r" % (where, expected, got))
    return False


def main():
    html_path, ens = sys.argv[1], sys.argv[2]
    with open(os.path.join(ens, "ensemble.json"), encoding="utf-8") as f:
        params = json.load(f)["parameters"]
    b = TreeBuilder()
    with open(html_path, encoding="utf-8") as f:
        b.feed(f.read())
    if b.root is None:
        print("no <details> block in", html_path)
        return 1
    tables = [c for c in b.root.children if c.tag == "table"]
    if not tables:
        print("no parameter table in the <details> block")
        return 1
    ok = same(params, table_to_value(tables[0]), "")
    count = [0]

    def leaves(v):
        if isinstance(v, dict):
            for x in v.values():
                leaves(x)
        elif isinstance(v, list):
            for x in v:
                leaves(x)
        else:
            count[0] += 1

    leaves(params)
    print("%s: %d parameters (%d scalar values) %s" % (html_path, len(params), count[0],
                                                     "all shown in full" if ok else "DIFFER"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
