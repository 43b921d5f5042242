# Detection matrices (the `detection:` section of a matrix): `crowdslam detect` of every configuration on
# every sequence, then `crowdslam detect-eval` against the sequence's ground truth, then one table.
# Included by workflows/Snakefile (M, R, PY, SCRIPTS come from there).

DET = M.detection or {"sequences": {}, "configs": {}, "iou": 0.5, "threads": 1}


def detect_command(wc):
    c, s = DET["configs"][wc.config], DET["sequences"][wc.seq]
    if c["public"]:  # the sequence's published detections, evaluated as they are
        return ["cp", s["public"], "{out}/det.txt"]
    return [M.crowdslam, "-q", "--json", "detect", "--dataset", s["path"], "--out", "{out}/det.txt",
            "--threads", str(DET["threads"])] + c["args"]


rule detect:
    input: BIN, seq=f"{R}/_sequences/{{seq}}.manifest" if M.inputs == "files" else []
    output: directory(f"{R}/detect/{{config}}/{{seq}}")
    params: command=detect_command
    log: f"{R}/_logs/detect/{{config}}/{{seq}}.log"
    threads: DET["threads"]
    resources: mem_mb=M.mem_mb, runtime=M.runtime_min
    shell: "{PY} {SCRIPTS}/run_job.py --out {output} --kind detect --stdout detect.json -- {params.command:q} 2> {log}"


rule detect_eval:
    input: BIN, det=f"{R}/detect/{{config}}/{{seq}}"
    output: f"{R}/detect/{{config}}/{{seq}}.eval.json"
    params: gt=lambda wc: DET["sequences"][wc.seq]["gt"], iou=DET["iou"]
    log: f"{R}/_logs/detect/{{config}}/{{seq}}.eval.log"
    shell:
        "{M.crowdslam} -q --json detect-eval --gt {params.gt:q} --det {input.det}/det.txt --iou {params.iou}"
        " > {output}.tmp 2> {log} && mv {output}.tmp {output}"


rule detect_table:
    input:
        evals=expand(f"{R}/detect/{{config}}/{{seq}}.eval.json", config=list(DET["configs"]),
                     seq=list(DET["sequences"])),
        matrix=f"{R}/matrix.json",
        script=os.path.join(SCRIPTS, "aggregate_detect.py"),
    output: csv=f"{R}/detect_table.csv", md=f"{R}/detect_table.md", json=f"{R}/detect_table.json"
    shell: "{PY} {input.script} --matrix {input.matrix} --results {R} --out {R}/detect_table"
