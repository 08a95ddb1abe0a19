"""The HTML report's reproducibility section: what it takes to get the same records again."""

from __future__ import annotations

import json
import shlex

from handsim.report import fmt
from handsim.report.markup import esc, simple_table
from handsim.report.records import RunRecords


def _pre_json(value: object) -> str:
    return f"<pre>{esc(json.dumps(value, indent=2, sort_keys=True))}</pre>"


def reproducibility(run: RunRecords, summary: dict) -> str:
    """The section: command line, versions, metric spec, run parameters, model and input hashes."""
    command = summary["command"]
    command_text = shlex.join(str(c) for c in command) if isinstance(command, list) else fmt.text(command)
    specs = "".join(
        f"<h4>metric spec used by {fmt.plural(s['trials'], 'trial')}</h4>{_pre_json(s['value'])}"
        for s in summary["metric_specs"]
    )
    if len(summary["versions"]) == 1 and summary["versions"][0]["value"] == summary["run_versions"]:
        versions = (
            f"<h3>Versions (the run and its {fmt.plural(summary['versions'][0]['trials'], 'trial')})</h3>"
            + _pre_json(summary["run_versions"])
        )
    else:
        versions = (
            (f"<h3>Run versions</h3>{_pre_json(summary['run_versions'])}" if summary["run_versions"] else "")
            + "<h3>Versions recorded per trial</h3>"
            + "".join(
                f"<h4>versions of {fmt.plural(v['trials'], 'trial')}</h4>{_pre_json(v['value'])}"
                for v in summary["versions"]
            )
        )
    models = [[r["id"], fmt.text(r.get("model_sha256"))] for r in run.records]
    inputs = [
        [r["id"], fmt.text(i.get("role")), fmt.text(i.get("path")), fmt.text(i.get("sha256"))]
        for r in run.records
        for i in r.get("inputs") or []
    ]
    return (
        '<section class="block" id="reproducibility"><h2>Reproducibility</h2>'
        f"<h3>Command line</h3><pre>{esc(command_text)}</pre>"
        f"<p>Dataset: <code>{esc(fmt.text(summary['dataset']))}</code>. Metric spec version: "
        f"<strong>{esc(', '.join(summary['metric_spec_versions']) or fmt.MISSING)}</strong>. "
        "Re-render this report from the records alone with "
        "<code>handsim report --render-only OUT/</code>.</p>"
        + versions
        + f"<h3>Metric spec</h3>{specs}"
        + (
            f"<h3>Run parameters</h3>{_pre_json(summary['run_parameters'])}"
            if summary["run_parameters"]
            else ""
        )
        + f"<details><summary>model hashes ({len(models)})</summary>"
        + simple_table(["trial", "model sha256"], models)
        + "</details>"
        + f"<details><summary>input hashes ({len(inputs)})</summary>"
        + simple_table(["trial", "role", "path", "sha256"], inputs)
        + "</details></section>"
    )
