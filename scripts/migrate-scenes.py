#!/usr/bin/env python3
"""Migrate grainflow scenes to the unified scene dialect (one dialect for fluid, coupled,
grain and MPM scenes).

Usage: scripts/migrate-scenes.py [--check] [--diff] FILE...

Each FILE is rewritten in place, and every change is printed. A file already in the new
dialect is left as it is, so running the tool twice changes nothing. Comments, blank lines,
key order and the way values are written are kept; a comment line directly above a key that
moves goes with it. What changes:

  [run] keeps the run length (steps or end_time_s) and the run mode (precision, backend,
        gpu_storage, kernel; stop_below_kinetic_energy_j_m;
        stop_below_specific_kinetic_energy_j_kg). The output keys move to a new [output]
        table right after it (omitted when nothing moves):
          output_every = N        -> every_steps = N          (dropped when 0, the default)
          output_every_s = X      -> every_s = X              (dropped when 0, the default)
          probe_every = N         -> probe_every_steps = N
          checkpoint_every = N    -> checkpoint_every_steps = N    (dropped when 0)
          checkpoint_minutes = M  -> checkpoint_every_minutes = M  (dropped when 0)
          fields, pictures, compression, picture_field, checkpoint_at_end: same names
  grain scenes: [region] min_m = [0, 0], max_m = [W, H]  ->  [domain] size_m = [W, H]
        (a region whose lower-left corner is not the origin is refused: move the scene first)
  MPM scenes:   [mpm] domain_m = [W, H], cell_size_m = h  ->  [domain] cells = [W/h, H/h],
        spacing_m = h (h written as before; W/h and H/h must be whole numbers), and
        [mpm] boundaries = { left, right, bottom, top } (or [mpm.boundaries])  ->  a top-level
        [boundaries] with west, east, south, north. Both tables go before [mpm].

Where the file is valid TOML, the result is parsed again and compared with the old scene
value by value (cells x spacing_m against domain_m to 1e-12); a file that does not pass is
not written. Options: --check writes nothing and exits 1 when a file needs migrating;
--diff prints a unified diff of each change (with --check too). Exit status 1 also when a
file could not be migrated (the message says why).
"""
import argparse
import copy
import difflib
import math
import re
import sys
import tomllib

# [run] key -> ([output] key, dropped when its value is 0).
MOVES = {
    "output_every": ("every_steps", True),
    "output_every_s": ("every_s", True),
    "fields": ("fields", False),
    "pictures": ("pictures", False),
    "compression": ("compression", False),
    "picture_field": ("picture_field", False),
    "probe_every": ("probe_every_steps", False),
    "checkpoint_every": ("checkpoint_every_steps", True),
    "checkpoint_minutes": ("checkpoint_every_minutes", True),
    "checkpoint_at_end": ("checkpoint_at_end", False),
}
SIDES = {"left": "west", "right": "east", "bottom": "south", "top": "north"}


class MigrationError(Exception):
    pass


# ---------------------------------------------------------------------------------------
# A line-level model of a TOML file: statements (one or more physical lines) grouped into
# sections (the comments directly above a header, the header, and the lines up to the next).

class Stmt:
    """kind: blank | comment | header | kv. `lines` are the physical lines, newline kept."""

    def __init__(self, kind, lines, key=None, name=None, array=False):
        self.kind, self.lines, self.key, self.name, self.array = kind, lines, key, name, array

    def text(self):
        return "".join(self.lines)


class Section:
    def __init__(self, prefix, header, body):
        self.prefix, self.header, self.body = prefix, header, body

    @property
    def name(self):
        return self.header.name if self.header else None

    def text(self):
        return "".join(s.text() for s in self.prefix + ([self.header] if self.header else []) + self.body)


HEADER = re.compile(r"^\s*(\[\[|\[)\s*([^\[\]]+?)\s*(\]\]|\])\s*(#.*)?$")


def scan(line, state):
    """Advance the string/bracket state over one physical line; returns the new state
    (depth, open multi-line string delimiter or None)."""
    depth, ml = state
    i, n = 0, len(line)
    while i < n:
        if ml:
            j = line.find(ml, i)
            if j < 0:
                return depth, ml
            i, ml = j + 3, None
            continue
        c = line[i]
        if c == "#":
            break
        if line.startswith('"""', i) or line.startswith("'''", i):
            ml = line[i:i + 3]
            i += 3
            continue
        if c in "\"'":
            j = i + 1
            while j < n and line[j] != c:
                j += 2 if (c == '"' and line[j] == "\\") else 1
            i = j + 1
            continue
        if c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        i += 1
    return depth, ml


def key_of(line):
    """The (dotted) key of a key = value line, without spaces."""
    i, n = 0, len(line)
    while i < n and line[i] != "=":
        if line[i] in "\"'":
            j = line.find(line[i], i + 1)
            i = n if j < 0 else j + 1
        else:
            i += 1
    if i >= n:
        raise MigrationError(f"cannot read the line {line.strip()!r}")
    return re.sub(r"\s*\.\s*", ".", line[:i].strip()), i


def parse(text):
    stmts, lines, k = [], text.splitlines(keepends=True), 0
    while k < len(lines):
        line = lines[k]
        s = line.strip()
        if not s:
            stmts.append(Stmt("blank", [line]))
        elif s.startswith("#"):
            stmts.append(Stmt("comment", [line]))
        elif s.startswith("["):
            m = HEADER.match(line.rstrip("\r\n"))
            if not m:
                raise MigrationError(f"cannot read the table header {s!r}")
            name = re.sub(r"\s*\.\s*", ".", m.group(2))
            stmts.append(Stmt("header", [line], name=name, array=m.group(1) == "[["))
        else:
            key, _ = key_of(line)
            group, state = [line], scan(line, (0, None))
            while (state[0] > 0 or state[1]) and k + 1 < len(lines):
                k += 1
                group.append(lines[k])
                state = scan(lines[k], state)
            stmts.append(Stmt("kv", group, key=key))
        k += 1
    sections, current = [], Section([], None, [])
    for st in stmts:
        if st.kind == "header":
            prefix = []
            while current.body and current.body[-1].kind == "comment":
                prefix.insert(0, current.body.pop())
            sections.append(current)
            current = Section(prefix, st, [])
        else:
            current.body.append(st)
    sections.append(current)
    return sections


def with_comments(body, i):
    """Indices of the key at body[i] and the comment lines directly above it."""
    j = i
    while j > 0 and body[j - 1].kind == "comment":
        j -= 1
    return list(range(j, i + 1))


def rename(st, new_key):
    first = st.lines[0]
    _, eq = key_of(first)
    indent = first[:len(first) - len(first.lstrip())]
    old = first[len(indent):eq].rstrip()
    return Stmt("kv", [indent + new_key + first[len(indent) + len(old):]] + st.lines[1:], key=new_key)


def value_of(st):
    text = st.text()
    _, eq = key_of(text)
    return tomllib.loads("v =" + text[eq + 1:])["v"]


def value_text(st):
    """The value as written, without the key, comment and newline (one-line values)."""
    line = st.lines[0].rstrip("\r\n")
    _, eq = key_of(line)
    rest = line[eq + 1:]
    end, i = len(rest), 0
    # Cut at the first # outside strings.
    while i < len(rest):
        c = rest[i]
        if c in "\"'":
            j = rest.find(c, i + 1)
            i = len(rest) if j < 0 else j + 1
            continue
        if c == "#":
            end = i
            break
        i += 1
    return rest[:end].strip(), rest[end:].strip()


def split_inline_table(text):
    """`{ a = 1, b = { c = 2 } }` -> ['a = 1', 'b = { c = 2 }']."""
    text = text.strip()
    if not (text.startswith("{") and text.endswith("}")):
        raise MigrationError(f"expected an inline table, got {text!r}")
    inner, parts, depth, start, i = text[1:-1], [], 0, 0, 0
    while i < len(inner):
        c = inner[i]
        if c in "\"'":
            j = inner.find(c, i + 1)
            i = len(inner) if j < 0 else j + 1
            continue
        if c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(inner[start:i].strip())
            start = i + 1
        i += 1
    parts.append(inner[start:].strip())
    return [p for p in parts if p]


def ends_blank(stmts):
    return bool(stmts) and stmts[-1].kind == "blank"


def strip_blank(stmts):
    out = list(stmts)
    while out and out[-1].kind == "blank":
        out.pop()
    return out


# ---------------------------------------------------------------------------------------
# The migration.

def migrate_text(text):
    """(new text, list of changes). Raises MigrationError when it cannot."""
    nl = "\r\n" if "\r\n" in text else "\n"
    if text and not text.endswith(("\n", "\r")):
        text += nl
    sections = parse(text)
    names = [s.name for s in sections]
    changes = []

    def line(s):
        return s + nl

    def find(name):
        hits = [i for i, s in enumerate(sections) if s.name == name and not s.header.array]
        if len(hits) > 1:
            raise MigrationError(f"[{name}] appears twice")
        return hits[0] if hits else None

    def section_keys(sec):
        return {st.key for st in sec.body if st.kind == "kv"}

    for i, s in enumerate(sections):
        if s.name is None:
            for st in s.body:
                if st.kind == "kv" and st.key.split(".")[0] in ("run", "region", "mpm", "output"):
                    raise MigrationError(f"dotted top-level key `{st.key}`: migrate it by hand")

    # [region] -> [domain] size_m (grain scenes).
    r = find("region")
    if r is not None:
        if find("domain") is not None:
            raise MigrationError("the scene has both [region] and [domain]")
        sec = sections[r]
        body, size = [], None
        for st in sec.body:
            if st.kind != "kv":
                body.append(st)
                continue
            if st.key == "min_m":
                lo = value_of(st)
                if any(float(x) != 0.0 for x in lo):
                    raise MigrationError(
                        f"[region] min_m = {lo}: the new [domain] starts at the origin; shift the "
                        "scene's coordinates by hand, then migrate")
                while body and body[-1].kind == "comment":  # its comments go with it
                    body.pop()
            elif st.key == "max_m":
                size = rename(st, "size_m")
                body.append(size)
            else:
                raise MigrationError(f"unknown key `{st.key}` in [region]")
        if size is None:
            raise MigrationError("[region] has no max_m")
        head = sec.header.lines[0]
        sec.header = Stmt("header", [head.replace("region", "domain", 1)], name="domain")
        sec.body = body
        changes.append(f"[region] -> [domain] size_m = {value_text(size)[0]} (min_m = [0, 0] dropped)")

    # MPM: [mpm] domain_m, cell_size_m, boundaries -> [domain], [boundaries].
    m = find("mpm")
    if m is not None:
        sec = sections[m]
        keys = section_keys(sec)
        new_sections = []
        if "domain_m" in keys or "cell_size_m" in keys:
            if "domain_m" not in keys or "cell_size_m" not in keys:
                raise MigrationError("[mpm] has only one of domain_m and cell_size_m")
            if find("domain") is not None:
                raise MigrationError("the scene has both [mpm] domain_m and [domain]")
            idx = {st.key: i for i, st in enumerate(sec.body) if st.kind == "kv"}
            dm, cs = sec.body[idx["domain_m"]], sec.body[idx["cell_size_m"]]
            size, h = value_of(dm), value_of(cs)
            h_text, h_comment = value_text(cs)
            _, d_comment = value_text(dm)
            if not (isinstance(h, (int, float)) and h > 0):
                raise MigrationError(f"cell_size_m = {h_text} is not a positive number")
            cells = []
            for d, w in zip("xy", size):
                n = round(w / h)
                if n < 1 or abs(n * h - w) > 1e-9 * max(abs(w), h):
                    raise MigrationError(
                        f"domain_m = {size} does not hold a whole number of {h_text} m cells in {d} "
                        f"({w / h:.6g}): fix the scene first")
                cells.append(n)
            comments = [sec.body[j] for j in with_comments(sec.body, idx["domain_m"])[:-1]]
            comments += [sec.body[j] for j in with_comments(sec.body, idx["cell_size_m"])[:-1]]
            drop = set(with_comments(sec.body, idx["domain_m"]) + with_comments(sec.body, idx["cell_size_m"]))
            sec.body = [st for j, st in enumerate(sec.body) if j not in drop]
            body = [Stmt("kv", [line(f"cells = [{cells[0]}, {cells[1]}]" + (f"  {d_comment}" if d_comment else ""))], key="cells"),
                    Stmt("kv", [line(f"spacing_m = {h_text}" + (f"  {h_comment}" if h_comment else ""))], key="spacing_m"),
                    Stmt("blank", [nl])]
            new_sections.append(Section(comments, Stmt("header", [line("[domain]")], name="domain"), body))
            changes.append(f"[mpm] domain_m = {list(size)}, cell_size_m = {h_text} -> "
                           f"[domain] cells = [{cells[0]}, {cells[1]}], spacing_m = {h_text}")
        # Boundaries: an inline table in [mpm], or [mpm.boundaries] (and its side tables).
        inline = [i for i, st in enumerate(sec.body) if st.kind == "kv" and st.key == "boundaries"]
        sub = [i for i, s in enumerate(sections) if s.name and (s.name == "mpm.boundaries" or s.name.startswith("mpm.boundaries."))]
        dotted = [st.key for st in sec.body if st.kind == "kv" and st.key.startswith("boundaries.")]
        if dotted:
            raise MigrationError(f"dotted keys {dotted} in [mpm]: migrate them by hand")
        if inline or sub:
            if find("boundaries") is not None:
                raise MigrationError("the scene has both MPM boundaries and a top-level [boundaries]")
            if inline and sub:
                raise MigrationError("[mpm] has both boundaries = {...} and [mpm.boundaries]")
        if inline:
            st = sec.body[inline[0]]
            if len(st.lines) > 1:
                raise MigrationError("boundaries = { ... } over several lines: migrate it by hand")
            value, comment = value_text(st)
            body = []
            for part in split_inline_table(value):
                k, eq = key_of(part)
                if k not in SIDES:
                    raise MigrationError(f"unknown side `{k}` in [mpm] boundaries")
                body.append(Stmt("kv", [line(f"{SIDES[k]} = {part[eq + 1:].strip()}")], key=SIDES[k]))
            body.append(Stmt("blank", [nl]))
            drop = with_comments(sec.body, inline[0])
            comments = [sec.body[j] for j in drop[:-1]]
            if comment:
                comments.append(Stmt("comment", [line(comment)]))
            sec.body = [s for j, s in enumerate(sec.body) if j not in drop]
            new_sections.append(Section(comments, Stmt("header", [line("[boundaries]")], name="boundaries"), body))
            changes.append("[mpm] boundaries = { left, right, bottom, top } -> [boundaries] west, east, south, north")
        if sub:
            moved = []
            for i in sub:
                s = sections[i]
                if s.header.array:
                    raise MigrationError(f"[[{s.name}]] is not a boundaries table")
                rest = s.name.split(".")[2:]
                if rest:
                    if rest[0] not in SIDES or len(rest) > 1:
                        raise MigrationError(f"unknown table [{s.name}]")
                    name = f"boundaries.{SIDES[rest[0]]}"
                else:
                    name = "boundaries"
                head = s.header.lines[0]
                head = head.replace(s.header.lines[0].strip().split("#")[0].strip(), f"[{name}]", 1)
                body = []
                for st in s.body:
                    if st.kind == "kv" and not rest:
                        if st.key not in SIDES:
                            raise MigrationError(f"unknown side `{st.key}` in [mpm.boundaries]")
                        body.append(rename(st, SIDES[st.key]))
                    else:
                        body.append(st)
                body = strip_blank(body) + [Stmt("blank", [nl])]
                moved.append(Section(s.prefix, Stmt("header", [head], name=name), body))
            # The sections before each removed table keep their own blank lines.
            for i in sorted(sub, reverse=True):
                del sections[i]
            new_sections += moved
            changes.append("[mpm.boundaries] left, right, bottom, top -> [boundaries] west, east, south, north")
        if new_sections:
            m = find("mpm")
            before = sections[m - 1] if m > 0 else None
            if before is not None and before.body and not ends_blank(before.body):
                # Compact files (no blank line before [mpm]): keep them compact.
                for s in new_sections:
                    s.body = strip_blank(s.body)
            sections[m:m] = new_sections

    # [run] output keys -> [output].
    r = find("run")
    if r is not None:
        sec = sections[r]
        moved, drop, notes = [], set(), []
        for i, st in enumerate(sec.body):
            if st.kind != "kv" or st.key not in MOVES:
                continue
            new, zero_default = MOVES[st.key]
            group = with_comments(sec.body, i)
            drop.update(group)
            v = value_of(st)
            if zero_default and not isinstance(v, bool) and v == 0:
                notes.append(f"[run] {st.key} = 0 dropped (the default)")
                continue
            moved += [sec.body[j] for j in group[:-1]] + [rename(st, new)]
            notes.append(f"[run] {st.key} -> [output] {new}" if new != st.key else f"[run] {st.key} -> [output]")
        if drop:
            sec.body = [st for j, st in enumerate(sec.body) if j not in drop]
            # Blank lines left inside the body where keys were: none doubled.
            cleaned = []
            for st in sec.body:
                if st.kind == "blank" and cleaned and cleaned[-1].kind == "blank":
                    continue
                cleaned.append(st)
            sec.body = cleaned
            o = find("output")
            if moved:
                if o is not None:
                    out = sections[o]
                    have = section_keys(out)
                    for st in moved:
                        if st.kind == "kv" and st.key in have:
                            raise MigrationError(f"[output] already has `{st.key}`")
                    core, tail = strip_blank(out.body), out.body[len(strip_blank(out.body)):]
                    out.body = core + moved + tail
                else:
                    core = strip_blank(sec.body)
                    tail = sec.body[len(core):]
                    sec.body = core + [Stmt("blank", [nl])]
                    out = Section([], Stmt("header", [line("[output]")], name="output"), moved + tail)
                    sections.insert(r + 1, out)
            changes += notes

    new = "".join(s.text() for s in sections)
    return new, changes


# ---------------------------------------------------------------------------------------
# Verification: the new scene, parsed, is the old one with the keys moved.

def expected(old):
    d = copy.deepcopy(old)
    run = d.get("run", {})
    out = d.get("output", {})
    for k, (new, zero_default) in MOVES.items():
        if k in run:
            v = run.pop(k)
            if zero_default and not isinstance(v, bool) and v == 0:
                continue
            out[new] = v
    if out:
        d["output"] = out
    if "region" in d:
        d["domain"] = {"size_m": d.pop("region")["max_m"]}
    mpm = d.get("mpm", {})
    if "domain_m" in mpm:
        w, h = mpm.pop("domain_m"), mpm.pop("cell_size_m")
        d["domain"] = {"cells": [round(x / h) for x in w], "spacing_m": h}
    if "boundaries" in mpm:
        d["boundaries"] = {SIDES[k]: v for k, v in mpm.pop("boundaries").items()}
    return d


def verify(old_text, new_text):
    """None when verified, a warning when the old text is not TOML, MigrationError if wrong."""
    try:
        old = tomllib.loads(old_text)
    except tomllib.TOMLDecodeError as e:
        return f"not valid TOML as it stands ({e}): migrated as text, values not verified"
    try:
        new = tomllib.loads(new_text)
    except tomllib.TOMLDecodeError as e:
        raise MigrationError(f"the migrated text does not parse ({e}); nothing written")
    want = expected(old)
    if new != want:
        raise MigrationError("the migrated scene differs from the old one; nothing written "
                             f"(got {sorted(new)}, expected {sorted(want)})")
    if "domain_m" in old.get("mpm", {}):
        w, h = old["mpm"]["domain_m"], old["mpm"]["cell_size_m"]
        for n, x in zip(new["domain"]["cells"], w):
            if abs(n * new["domain"]["spacing_m"] - x) > 1e-12 * abs(x):
                raise MigrationError(f"cells x spacing_m = {n * h} is not domain_m = {x}")
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+", metavar="FILE")
    ap.add_argument("--check", action="store_true", help="write nothing; exit 1 if a file needs migrating")
    ap.add_argument("--diff", action="store_true", help="print a unified diff of each change")
    a = ap.parse_args()
    status, todo = 0, 0
    for path in a.files:
        try:
            with open(path, encoding="utf-8", newline="") as f:
                old = f.read()
            new, changes = migrate_text(old)
            warning = verify(old, new) if new != old else None
        except (OSError, MigrationError, tomllib.TOMLDecodeError) as e:
            print(f"{path}: NOT MIGRATED: {e}", file=sys.stderr)
            status = 1
            continue
        if new == old:
            print(f"{path}: already in the new dialect")
            continue
        todo += 1
        verb = "would change" if a.check else "migrated"
        print(f"{path}: {verb}:")
        for c in changes:
            print(f"  {c}")
        if warning:
            print(f"  warning: {warning}")
        if a.diff:
            sys.stdout.writelines(difflib.unified_diff(
                old.splitlines(keepends=True), new.splitlines(keepends=True), path, path))
        if not a.check:
            with open(path, "w", encoding="utf-8", newline="") as f:
                f.write(new)
    if a.check and todo:
        status = 1
    sys.exit(status)


if __name__ == "__main__":
    main()
