import re
import unicodedata
from pathlib import Path

root = Path(".")


def slugify(value, sep="-"):
    value = unicodedata.normalize("NFKD", value).encode("ascii", "ignore").decode()
    value = re.sub(r"[^\w\s-]", "", value).strip().lower()
    return re.sub(rf"[{sep}\s]+", sep, value)


def strip_code(text):
    return re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)


def anchors(path):
    text = strip_code(path.read_text())
    seen = {}
    out = set()
    for m in re.finditer(r"^(#{1,6})\s+(.*?)\s*#*\s*$", text, flags=re.M):
        h = m.group(2)
        h = re.sub(r"\{[^}]*\}$", "", h)  # attr_list
        h = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", h)
        h = h.replace("`", "").replace("*", "")
        s = slugify(h)
        if s in seen:
            seen[s] += 1
            s2 = f"{s}_{seen[s]}"
        else:
            seen[s] = 0
            s2 = s
        out.add(s2)
    # explicit ids
    out |= set(re.findall(r"\{#([\w-]+)", text))
    out |= set(re.findall(r'id="([\w-]+)"', text))
    return out


pages = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
bad = []
for p in pages:
    text = strip_code(p.read_text())
    text = re.sub(r"`[^`\n]*`", "", text)
    for m in re.finditer(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", text):
        t = m.group(1)
        if re.match(r"[a-z]+:", t):
            continue
        line = text[: m.start()].count("\n") + 1
        f, _, a = t.partition("#")
        target = (p.parent / f).resolve() if f else p
        if f and not target.exists():
            # site-only links (reference/)
            bad.append((str(p.relative_to(root)), line, t, "missing file"))
            continue
        if a and target.suffix == ".md" and a not in anchors(target):
            bad.append((str(p.relative_to(root)), line, t, "missing anchor"))
for b in bad:
    print(*b)
