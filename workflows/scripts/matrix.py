"""Reads an evaluation matrix (workflows/matrices/*.yaml, already loaded by Snakemake as `config`) and
expands it into cases: dataset x settings x option set, each run `runs` times.

Used by the Snakefile and by the aggregation scripts; standard library only. The format is described
in workflows/README.md. Names (datasets, settings, option sets, detection configs) are made of letters,
digits, '_' and '-'; a case is named DATASET.SETTINGS.OPTIONS.
"""
import fnmatch
import hashlib
import itertools
import json
import os
import re
import shlex

NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*$")
MODES = ("accuracy", "timing")


class MatrixError(ValueError):
    pass


def repo_root():
    return os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _check_name(kind, name):
    if not NAME.match(str(name)):
        raise MatrixError(f"{kind} name {name!r}: use letters, digits, '_' and '-' (not first)")
    return str(name)


def _args(value):
    """Option arguments: a string (split like a shell) or a list."""
    if value is None:
        return []
    if isinstance(value, str):
        return shlex.split(value)
    if isinstance(value, list):
        return [str(v) for v in value]
    if isinstance(value, dict) and set(value) == {"args"}:  # a grid entry
        return _args(value["args"])
    raise MatrixError(f"arguments must be a string or a list, not {value!r}")


class _Keep(dict):
    """Template values; other {placeholders} (such as {dataset}) are left for later."""
    def __missing__(self, key):
        return "{" + key + "}"


def _grid(entries, kind):
    """Expands entries with `grid: {axis: [values]}`: the name and every string field are templates."""
    out = {}
    for name, entry in (entries or {}).items():
        entry = dict(entry) if isinstance(entry, dict) else entry
        if isinstance(entry, dict) and "grid" in entry:
            grids = entry.pop("grid")
            combos = []  # a grid, or a list of grids: the union of their products, in order
            for grid in grids if isinstance(grids, list) else [grids]:
                if not isinstance(grid, dict) or not grid:
                    raise MatrixError(f"{kind} {name!r}: grid: a mapping of axes to lists, or a list of them")
                axes = list(grid)
                combos += [list(zip(axes, values)) for values in itertools.product(*(grid[a] for a in axes))]
            for combo in combos:
                sub = _Keep(combo)
                fill = lambda v: v.format_map(sub) if isinstance(v, str) else (
                    [fill(x) for x in v] if isinstance(v, list) else (
                        {k: fill(x) for k, x in v.items()} if isinstance(v, dict) else v))
                out[_check_name(kind, name.format_map(sub))] = fill(entry)
        else:
            out[_check_name(kind, name)] = entry
    return out


class Matrix:
    def __init__(self, config, repo=None, results=None):
        self.repo = repo or repo_root()
        c = config
        self.name = _check_name("matrix", c.get("matrix") or "")
        self.title = c.get("title", self.name)
        self.mode = c.get("mode", "accuracy")
        if self.mode not in MODES:
            raise MatrixError(f"mode {self.mode!r}: accuracy or timing")
        self.runs = int(c.get("runs", 1))
        self.shared = os.path.abspath(os.path.expanduser(str(
            c.get("shared") or os.environ.get("CROWDSLAM_SHARED") or os.path.join(self.repo, "..", "shared"))))
        self.crowdslam = self.path(c.get("crowdslam", "build/apps/crowdslam/crowdslam"))
        self.results = results or str(c.get("results", "out/eval"))
        self.timing_threads = int(c.get("timing_threads", 2))
        self.mem_mb = int(c.get("mem_mb", 1024))
        self.runtime_min = int(c.get("runtime_min", 30))
        # files: the binary, settings and on-disk datasets are input files (a shared file system);
        # params: they are not (a cluster without one, e.g. Kubernetes with a remote provider): a
        # fingerprint (build_id, the settings' contents, the dataset's manifest when readable) is a param.
        self.inputs = c.get("inputs", "files")
        if self.inputs not in ("files", "params"):
            raise MatrixError(f"inputs {self.inputs!r}: files or params")
        self.build_id = str(c.get("build_id", ""))
        self.compare_by = c.get("compare_by", "dataset")
        if self.compare_by not in ("dataset", "settings", "options"):
            raise MatrixError(f"compare_by {self.compare_by!r}: dataset, settings or options")
        self.datasets = {}
        for name, d in _grid(c.get("datasets"), "dataset").items():
            self.datasets[name] = self._dataset(name, d)
        for name, d in self.datasets.items():
            if d["kind"] == "variant" and d["of"] not in self.datasets:
                raise MatrixError(f"dataset {name}: variant of unknown dataset {d['of']!r}")
        self.settings = {}
        for name, s in _grid(c.get("settings") or {"default": None}, "settings").items():
            self.settings[name] = self._settings(name, s)
        self.options = {name: _args(o) for name, o in _grid(c.get("options") or {"default": ""}, "option set").items()}
        self.cases = self._cases(c.get("cases"))
        self.detection = self._detection(c.get("detection"))
        if not self.cases and not self.detection:
            raise MatrixError(f"matrix {self.name}: no case and no detection configuration")

    def path(self, p):
        p = str(p).format(shared=self.shared, repo=self.repo)
        return os.path.normpath(p if os.path.isabs(p) else os.path.join(self.repo, p))

    def _dataset(self, name, d):
        if isinstance(d, str):
            d = {"path": d}
        extra = _args(d.get("args"))
        settings = self.path(d["settings"]) if d.get("settings") else None
        base = {"args": extra, "settings": settings, "baseline": d.get("baseline"), "label": d.get("label", name)}
        gen = os.path.join(self.results, self.name, "_datasets", name)
        if "path" in d:
            return dict(base, kind="path", path=self.path(d["path"]))
        if "synth" in d:
            return dict(base, kind="synth", path=gen, synth=_args(d["synth"]))
        if "variant" in d:
            v = d["variant"]
            return dict(base, kind="variant", path=gen, of=str(v["of"]), variant=_args(v.get("args")))
        raise MatrixError(f"dataset {name}: needs path, synth or variant")

    def _settings(self, name, s):
        if s is None or s == "default":
            return {"kind": "dataset", "set": {}}
        if isinstance(s, str):
            return {"kind": "file", "path": self.path(s), "set": {}}
        lines = {str(k): str(v) for k, v in (s.get("set") or {}).items()}
        base = s.get("base", "dataset")
        return {"kind": "derived", "base": None if base == "dataset" else self.path(base), "set": lines}

    def _cases(self, blocks):
        if not self.datasets:
            return {}
        blocks = blocks if blocks is not None else [{}]
        cases = {}
        axes = (("datasets", self.datasets), ("settings", self.settings), ("options", self.options))
        for block in blocks:
            picked = []
            for key, known in axes:
                patterns = block.get(key, ["*"])
                patterns = [patterns] if isinstance(patterns, str) else patterns
                names = [n for n in known if any(fnmatch.fnmatchcase(n, p) for p in patterns)]
                if not names:
                    raise MatrixError(f"cases: {key} {patterns} match nothing")
                picked.append(names)
            for d, s, o in itertools.product(*picked):
                cases[f"{d}.{s}.{o}"] = {"dataset": d, "settings": s, "options": o}
        return cases

    def _detection(self, det):
        if not det:
            return None
        seqs = {}
        for name, s in _grid(det.get("sequences"), "sequence").items():
            s = {"path": s} if isinstance(s, str) else s
            path = self.path(s["path"])
            seqs[name] = {"path": path, "gt": os.path.join(path, s.get("gt", "gt/gt.txt")),
                          "public": os.path.join(path, s.get("public", "det/det.txt"))}
        configs = {}
        for name, a in _grid(det.get("configs"), "detection config").items():
            configs[name] = {"public": True, "args": []} if a == "public" else {"public": False, "args": _args(a)}
        return {"sequences": seqs, "configs": configs, "iou": float(det.get("iou", 0.5)),
                "threads": int(det.get("threads", 1))}

    # What a run job needs.
    def settings_file(self, case):
        """The settings file a case runs with (None: the dataset's own settings.yaml is found by crowdslam)."""
        c = self.cases[case]
        s, d = self.settings[c["settings"]], self.datasets[c["dataset"]]
        if s["kind"] == "file":
            return s["path"]
        if s["kind"] == "derived":
            return os.path.join(self.results, self.name, "_settings", c["settings"], c["dataset"] + ".yaml")
        return d["settings"]

    def derived_base(self, settings, dataset):
        s, d = self.settings[settings], self.datasets[dataset]
        return s["base"] or d["settings"] or os.path.join(d["path"], "settings.yaml")

    def run_args(self, case):
        c = self.cases[case]
        d = self.datasets[c["dataset"]]
        args = ["--dataset", d["path"]]
        settings = self.settings_file(case)
        if settings:
            args += ["--settings", settings]
        if self.mode == "accuracy":
            args.append("--sequential")
        args += d["args"] + self.options[c["options"]]
        return [a.replace("{dataset}", d["path"]) for a in args]

    def fingerprint(self, case):
        """What the result of a case depends on, as text (inputs: params)."""
        c = self.cases[case]
        d = self.datasets[c["dataset"]]
        parts = [f"build {self.build_id}", " ".join(self.run_args(case))]
        for path in (self.settings_file(case), self.settings[c["settings"]].get("base")):
            if path and os.path.isfile(path):
                with open(path, "rb") as f:
                    parts.append(hashlib.sha256(f.read()).hexdigest())
        if d["kind"] == "path" and os.path.exists(d["path"]):
            parts.append(json.loads(dataset_manifest(d["path"]))["sha256"])
        return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]

    def threads(self):
        return 1 if self.mode == "accuracy" else self.timing_threads

    def describe(self):
        """Everything the tables show about the matrix (written to RESULTS/MATRIX/matrix.json)."""
        return {"matrix": self.name, "title": self.title, "mode": self.mode, "runs": self.runs,
                "compare_by": self.compare_by,
                "crowdslam": self.crowdslam,
                "cases": {k: dict(v, args=[self.shown(a) for a in self.run_args(k)],
                                  label=self.datasets[v["dataset"]]["label"],
                                  baseline=self.baseline(k))
                          for k, v in self.cases.items()},
                "detection": self.detection}

    def shown(self, arg):
        """An argument as the tables show it: ../shared, paths in the repository relative to it, RESULTS/."""
        for prefix, name in ((os.path.abspath(self.results), "RESULTS"), (self.shared, "../shared"),
                             (self.results.rstrip("/"), "RESULTS"), (self.repo + "/", "")):
            if arg.startswith(prefix):
                return name + arg[len(prefix):]
        return arg

    def baseline(self, case):
        """The case whose median ATE this case is divided by (dataset `baseline: {dataset, options}`)."""
        c = self.cases[case]
        b = self.datasets[c["dataset"]]["baseline"]
        if not b:
            return None
        options = b.get("options", c["options"])
        options = options.get(c["options"]) if isinstance(options, dict) else options
        if options is None:
            return None
        other = f"{b['dataset']}.{c['settings']}.{options}"
        return other if other in self.cases else None


def dataset_manifest(path):
    """A short fingerprint of a dataset directory (or file): file count, bytes, hash of names/sizes/mtimes.
    Rewritten only when it changes, so that its mtime marks the last change of the dataset."""
    h = hashlib.sha256()
    count = total = 0
    if os.path.isfile(path):
        st = os.stat(path)
        h.update(f"{os.path.basename(path)} {st.st_size} {st.st_mtime_ns}\n".encode())
        count, total = 1, st.st_size
    else:
        for root, dirs, files in os.walk(path, followlinks=True):
            dirs.sort()
            for f in sorted(files):
                p = os.path.join(root, f)
                try:
                    st = os.stat(p)
                except OSError:
                    continue
                h.update(f"{os.path.relpath(p, path)} {st.st_size} {st.st_mtime_ns}\n".encode())
                count, total = count + 1, total + st.st_size
    return json.dumps({"path": path, "files": count, "bytes": total, "sha256": h.hexdigest()}, indent=1) + "\n"


def write_if_changed(path, text):
    try:
        with open(path) as f:
            if f.read() == text:
                return
    except OSError:
        pass
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)
