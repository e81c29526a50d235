import importlib
import inspect
import pkgutil
import re
import warnings
from pathlib import Path

import poc_env

warnings.filterwarnings("ignore")
index = {}
for m in pkgutil.walk_packages(poc_env.__path__, "poc_env."):
    try:
        mod = importlib.import_module(m.name)
    except Exception:
        continue
    for n, obj in vars(mod).items():
        if callable(obj) and getattr(obj, "__module__", "").startswith("poc_env"):
            index.setdefault(n, set()).add(obj)
root = Path(".")
pages = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
for p in pages:
    t = p.read_text()
    for m in re.finditer(r"`([A-Za-z_][\w.]*)\(([^`]*)\)`", t):
        name = m.group(1).split(".")[-1]
        kws = re.findall(r"(?<![\w.])(\w+)=", m.group(2))
        if not kws or name not in index:
            continue
        ok_any = False
        msgs = []
        for obj in index[name]:
            try:
                sig = inspect.signature(obj)
            except Exception:
                ok_any = True
                break
            params = sig.parameters
            if any(pp.kind == pp.VAR_KEYWORD for pp in params.values()):
                ok_any = True
                break
            bad = [k for k in kws if k not in params]
            if not bad:
                ok_any = True
                break
            msgs.append(f"{obj.__module__}.{name}: no {bad}")
        if not ok_any:
            print(p.name, t[: m.start()].count("\n") + 1, m.group(0)[:90], "::", msgs)
