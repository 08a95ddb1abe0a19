"""The HTML report's stylesheet (inlined into the page; no external fonts or files)."""

from __future__ import annotations

STATUS_COLOURS: dict[str, str] = {
    "held": "#2f8f5b",
    "ok": "#2f8f5b",
    "not held": "#e0a030",
    "followed": "#3a9e6e",
    "lost": "#d4862a",
    "not judged": "#8c96a3",
    "ran": "#6b8fc7",
    "flagged": "#7a7f87",
    "diverged": "#b45fc4",
    "error": "#c8423b",
}

CSS = """
:root { --ink: #1d232b; --muted: #5d6875; --line: #dde2e8; --paper: #ffffff; --bg: #f4f6f8;
  --accent: #1f5fa8; --ok: #2f8f5b; --warn: #e0a030; --bad: #c8423b; --div: #b45fc4; }
* { box-sizing: border-box; }
html { scroll-behavior: auto; }
body { margin: 0; background: var(--bg); color: var(--ink);
  font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif; }
header.top { background: #18324f; color: #fff; padding: 18px 28px 14px; }
header.top h1 { margin: 0 0 4px; font-size: 22px; font-weight: 650; letter-spacing: .2px; }
header.top .sub { color: #c9d6e6; font-size: 13px; word-break: break-all; }
nav.toc { position: sticky; top: 0; z-index: 5; background: #fff; border-bottom: 1px solid var(--line);
  padding: 8px 28px; display: flex; flex-wrap: wrap; gap: 6px 18px; font-size: 13px; }
nav.toc a { color: var(--accent); text-decoration: none; font-weight: 550; }
nav.toc a:hover { text-decoration: underline; }
main { max-width: 1240px; margin: 0 auto; padding: 18px 28px 40px; }
section.block { background: var(--paper); border: 1px solid var(--line); border-radius: 8px;
  padding: 14px 20px 18px; margin: 0 0 18px; }
h2 { font-size: 18px; margin: 2px 0 10px; }
h3 { font-size: 15px; margin: 16px 0 8px; }
h4 { font-size: 13px; margin: 12px 0 6px; color: var(--muted); text-transform: uppercase;
  letter-spacing: .4px; }
p.note, .muted { color: var(--muted); }
p.note { font-size: 13px; margin: 4px 0 10px; }
a { color: var(--accent); }
code, pre { font: 12px/1.4 ui-monospace, "DejaVu Sans Mono", Menlo, Consolas, monospace; }
pre { background: #f6f8fa; border: 1px solid var(--line); border-radius: 6px; padding: 8px 10px;
  overflow-x: auto; white-space: pre-wrap; word-break: break-word; margin: 6px 0; }
.cards { display: flex; flex-wrap: wrap; gap: 10px; margin: 4px 0 14px; }
.card { border: 1px solid var(--line); border-radius: 8px; padding: 8px 14px; min-width: 120px;
  background: #fbfcfd; }
.card .v { font-size: 22px; font-weight: 650; }
.card .k { font-size: 12px; color: var(--muted); }
.card.ok .v { color: var(--ok); }
.card.diverged .v { color: var(--div); }
.card.error .v { color: var(--bad); }
.scroll { overflow-x: auto; max-width: 100%; }
.scroll.tall { max-height: 560px; overflow-y: auto; }
table.data { border-collapse: collapse; font-size: 12.5px; width: 100%; }
table.data th, table.data td { padding: 4px 7px; border-bottom: 1px solid var(--line); text-align: left;
  white-space: nowrap; vertical-align: top; }
table.data th { background: #eef2f6; position: sticky; top: 0; font-weight: 600; white-space: normal;
  vertical-align: bottom; min-width: 52px; }
table.data th[title] { cursor: help; text-decoration: underline dotted #9aa5b1; }
table.data td.n, table.data th.n { text-align: right; font-variant-numeric: tabular-nums; }
table.data tbody tr:nth-child(even) { background: #fafbfc; }
table.data tbody tr:hover { background: #eef5ff; }
table.data tr.total td { font-weight: 650; border-top: 2px solid #c5ccd4; background: #f3f6f9; }
table.data td.t:last-child:not(:first-child) { white-space: normal; min-width: 240px; }
.badge { display: inline-block; padding: 0 7px; border-radius: 9px; font-size: 11.5px; font-weight: 600;
  color: #fff; line-height: 18px; }
.badge.ok, .badge.held { background: var(--ok); } .badge.diverged { background: var(--div); }
.badge.error { background: var(--bad); } .badge.not-held { background: var(--warn); color: #3a2a00; }
.badge.ran { background: #6b8fc7; } .badge.followed { background: var(--ok); }
.badge.lost { background: var(--warn); color: #3a2a00; }
.grid2 { display: grid; grid-template-columns: repeat(auto-fit, minmax(430px, 1fr)); gap: 12px 18px; }
.grid2 > div, .grid2 > figure { min-width: 0; }
svg.chart { max-width: 100%; height: auto; display: block; background: #fff; }
svg.chart text { font: 11px system-ui, "DejaVu Sans", sans-serif; fill: #39424c; }
svg.chart text.title { font-size: 12.5px; font-weight: 650; fill: var(--ink); }
svg.chart text.label { fill: var(--muted); }
svg.chart text.marker { font-size: 10px; fill: #9a3d1c; paint-order: stroke; stroke: #fff; stroke-width: 3px;
  stroke-linejoin: round; }
svg.chart text.empty { fill: #8a939c; font-size: 13px; }
svg.chart .grid { stroke: #e6e9ed; stroke-width: 1; }
svg.chart .axis { stroke: #8b949e; stroke-width: 1; }
svg.chart .line { fill: none; stroke-width: 1.6; stroke-linejoin: round; stroke-linecap: round; }
svg.chart .ref { stroke: #c0572b; stroke-width: 1; stroke-dasharray: 4 3; }
svg.chart .span { fill: #fdf1d2; }
svg.chart .bar { stroke: none; }
svg.chart .area { stroke: none; opacity: .85; }
ol.worst { margin: 6px 0; padding-left: 28px; }
ol.worst li { margin: 3px 0; }
section.trial { background: var(--paper); border: 1px solid var(--line); border-radius: 8px;
  padding: 12px 20px 16px; margin: 0 0 14px; content-visibility: auto; contain-intrinsic-size: auto 900px; }
section.trial:target { border-color: var(--accent); box-shadow: 0 0 0 3px #cfe0f5; }
section.trial h3 { margin: 2px 0 4px; font-size: 16px; display: flex; flex-wrap: wrap; align-items: center;
  gap: 8px; word-break: break-all; }
section.trial h3 .rank { font-size: 12px; font-weight: 500; color: var(--muted); }
section.trial .top { float: right; font-size: 12px; }
.meta { color: var(--muted); font-size: 13px; margin-bottom: 6px; }
.reason { margin: 4px 0 8px; padding: 5px 10px; border-left: 4px solid var(--warn); background: #fff8e8;
  font-size: 13px; }
.reason.error { border-color: var(--bad); background: #fdeeee; }
.reason.diverged { border-color: var(--div); background: #f8eefa; }
dl.numbers { display: grid; grid-template-columns: repeat(auto-fill, minmax(190px, 1fr)); gap: 4px 16px;
  margin: 8px 0 12px; font-size: 12.5px; }
dl.numbers div { display: flex; justify-content: space-between; border-bottom: 1px dotted var(--line);
  gap: 8px; }
dl.numbers dt { color: var(--muted); } dl.numbers dd { margin: 0; font-variant-numeric: tabular-nums;
  font-weight: 550; }
.frames { display: grid; grid-template-columns: repeat(auto-fill, minmax(240px, 1fr)); gap: 10px;
  margin: 6px 0; }
.frames figure { margin: 0; border: 1px solid var(--line); border-radius: 6px; padding: 4px;
  background: #fafbfc; }
.frames img { display: block; width: 100%; height: auto; border-radius: 4px; }
.frames figcaption { font-size: 11.5px; color: var(--muted); text-align: center; margin-top: 2px; }
.problem { color: var(--bad); font-size: 12px; }
details { margin: 6px 0; }
details > summary { cursor: pointer; color: var(--accent); font-size: 13px; }
ul.plain { margin: 4px 0; padding-left: 20px; font-size: 13px; }
footer { color: var(--muted); font-size: 12px; text-align: center; padding: 12px; }
"""
