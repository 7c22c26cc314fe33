#include "session/live_view_page.hpp"

namespace flutterscan::session {

namespace {

constexpr std::string_view kPage = R"html(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>flutterscan live view</title>
<style>
body { font-family: sans-serif; margin: 1em 1.5em; color: #222; background: #fafafa; }
h1 { font-size: 1.3em; margin: 0 0 0.2em 0; }
h2 { font-size: 1.05em; margin: 1.2em 0 0.4em 0; }
.line { color: #555; font-size: 0.9em; }
.state { display: inline-block; padding: 0.1em 0.6em; border-radius: 0.8em; background: #ddd; }
.state.armed { background: #b7e4b7; }
.figures { display: flex; flex-wrap: wrap; gap: 0.6em; margin-top: 0.8em; }
.figure { background: #fff; border: 1px solid #ddd; border-radius: 4px; padding: 0.4em 0.8em;
          min-width: 8em; }
.figure .value { font-size: 1.4em; font-weight: bold; }
.figure .label { font-size: 0.8em; color: #666; }
.pictures { display: grid; grid-template-columns: 1fr 1fr; gap: 1em; max-width: 1400px; }
.frame { position: relative; }
.frame img { display: block; width: 100%; background: #000; }
.frame img:not([src]) { visibility: hidden; }
.frame svg { position: absolute; left: 0; top: 0; width: 100%; height: 100%; }
.caption { font-size: 0.85em; color: #555; }
polygon { fill: none; stroke: #0f0; stroke-width: 3; vector-effect: non-scaling-stroke; }
text { fill: #0f0; font-size: 14px; paint-order: stroke; stroke: #000; stroke-width: 3px; }
table { border-collapse: collapse; font-size: 0.9em; background: #fff; }
th, td { border: 1px solid #ddd; padding: 0.2em 0.5em; text-align: left; }
td.noread { color: #b00; font-weight: bold; }
.noreads { display: flex; flex-wrap: wrap; gap: 0.8em; }
.noreads figure { margin: 0; font-size: 0.8em; }
.noreads img { display: block; max-width: 300px; max-height: 160px; background: #000; }
#connection { color: #b00; }
footer { margin-top: 1.5em; font-size: 0.8em; color: #777; }
</style>
</head>
<body>
<h1>flutterscan live view <span id="state" class="state">starting</span></h1>
<div class="line" id="line"></div>
<div id="connection"></div>
<div class="figures">
  <div class="figure"><div class="value" id="frames-processed">0</div>
    <div class="label">frames processed of <span id="frames-captured">0</span> captured</div></div>
  <div class="figure"><div class="value" id="frames-dropped">0</div>
    <div class="label">dropped (processing behind); failed <span id="frames-failed">0</span></div></div>
  <div class="figure"><div class="value" id="fps">0</div>
    <div class="label">fps (last 2 s)</div></div>
  <div class="figure"><div class="value" id="latency-p50">0</div>
    <div class="label">latency p50 ms; p99 <span id="latency-p99">0</span> ms</div></div>
  <div class="figure"><div class="value"><span id="objects-read">0</span> /
    <span id="objects">0</span></div>
    <div class="label">objects read (<span id="read-rate">0</span>)</div></div>
  <div class="figure"><div class="value" id="minute-read-rate">-</div>
    <div class="label">read rate, last minute (<span id="minute-read">0</span> of
      <span id="minute-objects">0</span>)</div></div>
  <div class="figure"><div class="value" id="decode-rate">-</div>
    <div class="label">mean decode rate per object</div></div>
  <div class="figure"><div class="value" id="no-reads">0</div>
    <div class="label">NO-READs</div></div>
</div>

<h2>Latest frame</h2>
<div class="pictures">
  <div><div class="frame"><img id="captured" alt="latest frame as captured"></div>
    <div class="caption">as captured</div></div>
  <div><div class="frame"><img id="fused" alt="latest frame fused">
    <svg id="overlay" preserveAspectRatio="none"></svg></div>
    <div class="caption">fused, with the codes read</div></div>
</div>
<div class="caption" id="picture-caption">no frame yet</div>

<h2>Guard flags</h2>
<table><thead><tr><th>flag</th><th>frames</th></tr></thead><tbody id="flags"></tbody></table>
<div class="line">last frame: <span id="last-flags">none</span></div>

<h2>Latest objects</h2>
<table>
<thead><tr><th>object</th><th>status</th><th>value</th><th>format</th><th>decoded / seen</th>
<th>grade</th><th>time (UTC)</th></tr></thead>
<tbody id="objects-table"></tbody>
</table>

<h2>Recent NO-READs</h2>
<div class="noreads" id="noreads"></div>

<footer>Read-only view of the running session. Updated <span id="updated">never</span>
(<span id="updates">0</span> updates). <a href="metrics">metrics</a></footer>

<script>
"use strict";
const $ = (id) => document.getElementById(id);
const svgNs = "http://www.w3.org/2000/svg";
let pictureShown = -1;
let noReadsShown = "";
let updates = 0;

function percent(x) { return (100 * x).toFixed(1) + "%"; }
function setText(id, text) { $(id).textContent = String(text); }
function cell(row, text, className) {
  const td = document.createElement("td");
  td.textContent = text === undefined || text === null ? "" : String(text);
  if (className) td.className = className;
  row.appendChild(td);
}

function showLine(s) {
  const l = s.line || {};
  const parts = [];
  if (l.camera) parts.push("camera " + l.camera);
  if (l.controller) parts.push("controller " + l.controller);
  if (l.code) parts.push("code " + l.code);
  if (l.scheme) parts.push("scheme " + l.scheme.scheme + " (expected margin " +
                           l.scheme.expected_margin_db.toFixed(1) + " dB)");
  if (l.light) parts.push("light " + l.light);
  if (l.method) parts.push(l.method);
  if (s.folder) parts.push("folder " + s.folder);
  setText("line", parts.join(" \u00b7 "));
  setText("state", s.state);
  $("state").className = "state " + s.state;
}

function showFigures(s) {
  setText("frames-processed", s.frames.processed);
  setText("frames-captured", s.frames.captured);
  setText("frames-dropped", s.frames.dropped);
  setText("frames-failed", s.frames.failed);
  setText("fps", s.fps.toFixed(1));
  setText("latency-p50", s.latency_ms.p50.toFixed(1));
  setText("latency-p99", s.latency_ms.p99.toFixed(1));
  const o = s.objects;
  setText("objects-read", o.read);
  setText("objects", o.total);
  setText("read-rate", percent(o.read_rate));
  setText("no-reads", o.no_read);
  setText("decode-rate", o.total > 0 ? percent(o.mean_decode_rate) : "-");
  const m = o.last_minute;
  setText("minute-read", m.read);
  setText("minute-objects", m.total);
  setText("minute-read-rate", m.total > 0 ? percent(m.read_rate) : "-");
}

function showPicture(p) {
  if (!p || p.sequence === pictureShown) return;
  pictureShown = p.sequence;
  $("captured").src = "frame/captured.jpg?frame=" + p.sequence;
  $("fused").src = "frame/fused.jpg?frame=" + p.sequence;
  const svg = $("overlay");
  svg.setAttribute("viewBox", "0 0 " + p.width + " " + p.height);
  svg.replaceChildren();
  const codes = p.about.decoded || [];
  for (const code of codes) {
    const corners = code.corners || [];
    if (corners.length === 0) continue;
    const polygon = document.createElementNS(svgNs, "polygon");
    polygon.setAttribute("points", corners.map((c) => c[0] + "," + c[1]).join(" "));
    svg.appendChild(polygon);
    const label = document.createElementNS(svgNs, "text");
    label.setAttribute("x", corners[0][0]);
    label.setAttribute("y", Math.max(14, corners[0][1] - 4));
    label.textContent = code.text;
    svg.appendChild(label);
  }
  const flags = p.about.flags || [];
  setText("picture-caption", "frame " + p.sequence + ": " + codes.length + " code(s) read" +
          (p.about.windows ? " in " + p.about.windows + " window(s)" : "") +
          (codes.length ? ": " + codes.map((c) => c.format + " " + c.text).join(", ") : "") +
          (flags.length ? "; flags " + flags.join(", ") : ""));
}

function showFlags(s) {
  const body = $("flags");
  body.replaceChildren();
  const flags = Object.entries(s.flags);
  if (flags.length === 0) flags.push(["none", 0]);
  for (const [flag, count] of flags) {
    const row = document.createElement("tr");
    cell(row, flag);
    cell(row, count);
    body.appendChild(row);
  }
  setText("last-flags", s.last_flags.length ? s.last_flags.join(", ") : "none");
}

function showObjects(s) {
  const body = $("objects-table");
  body.replaceChildren();
  for (const r of s.recent_objects) {
    const row = document.createElement("tr");
    cell(row, r.object);
    cell(row, r.status, r.status === "READ" ? "" : "noread");
    cell(row, r.value);
    cell(row, r.format);
    cell(row, r.decoded_frames + " / " + r.frames + " (" +
         percent(r.frames > 0 ? r.decoded_frames / r.frames : 0) + ")");
    cell(row, r.quality && r.quality.grade ? r.quality.grade : "");
    cell(row, r.time);
    body.appendChild(row);
  }
}

function showNoReads(s) {
  const shown = s.no_reads.map((r) => r.object).join(",");
  if (shown === noReadsShown) return;  // their pictures are fetched once
  noReadsShown = shown;
  const box = $("noreads");
  box.replaceChildren();
  for (const r of s.no_reads) {
    const figure = document.createElement("figure");
    if (r.frame_file) {
      const img = document.createElement("img");
      img.src = "files/" + r.frame_file.replace(/\.png$/, ".fused.png");
      img.alt = "object " + r.object + ", frame " + r.sequence;
      figure.appendChild(img);
    }
    const caption = document.createElement("figcaption");
    caption.textContent = "object " + r.object + ", frame " + r.sequence + ", " + r.time +
                          (r.frame_file ? "" : " (frame not kept)");
    figure.appendChild(caption);
    box.appendChild(figure);
  }
}

async function update() {
  try {
    const response = await fetch("state.json", {cache: "no-store"});
    const s = await response.json();
    showLine(s);
    showFigures(s);
    showPicture(s.picture);
    showFlags(s);
    showObjects(s);
    showNoReads(s);
    updates += 1;
    setText("updates", updates);
    setText("updated", new Date().toISOString().substring(11, 19) + " UTC");
    setText("connection", "");
  } catch (e) {
    setText("connection", "No answer from the session (it has ended, or the line is down).");
  }
  setTimeout(update, 250);
}
update();
</script>
</body>
</html>
)html";

}  // namespace

std::string_view live_view_page() {
  return kPage;
}

}  // namespace flutterscan::session
