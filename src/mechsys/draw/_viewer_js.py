r"""The HTML viewer's stylesheet and JavaScript, written for mechsys (no third-party code).

Renderer: Canvas 2D. Every frame, vertices are placed (rigid items: body pose times local
vertices; others: stored per frame), projected (perspective or orthographic camera on a
turntable orbit about the scene's "up" axis: z for spatial models, y for planar ones), and
all faces, line segments and markers are sorted far-to-near (planar models: by layer,
then depth) and painted. Faces get flat two-sided Lambert shading from a light near the
viewer. After every paint the canvas carries ``data-probe``: the projected centre and
extent of every face item, so automated tests can check where bodies land on screen.
"""

VIEWER_CSS = """
html,body{margin:0;height:100%;overflow:hidden;background:#fff;color:#222;
font:13px system-ui,-apple-system,"Segoe UI",sans-serif}
#view{position:absolute;left:0;top:0;width:100%;height:calc(100% - 44px);touch-action:none;
cursor:grab;display:block}
#view.drag{cursor:grabbing}
#bar{position:absolute;left:0;right:0;bottom:0;height:44px;display:flex;align-items:center;
gap:10px;padding:0 10px;background:#f2f2f2;border-top:1px solid #d8d8d8;box-sizing:border-box}
#bar button{min-width:34px;height:28px}
#slider{flex:1;min-width:60px}
#info{position:absolute;left:10px;top:8px;pointer-events:none}
#time{font-variant-numeric:tabular-nums;margin-left:8px}
#help{position:absolute;right:10px;top:8px;color:#999;font-size:11px;pointer-events:none;
text-align:right;max-width:45%}
#err{position:absolute;left:10px;top:32px;color:#b00;white-space:pre-wrap}
"""

VIEWER_JS = r"""
(function () {
"use strict";
var errBox = document.getElementById("err");
window.addEventListener("error", function (e) { errBox.textContent = "viewer error: " + e.message; });

var D = JSON.parse(document.getElementById("mechsys-data").textContent);
function dec(b64, T) {
  if (!b64) return null;
  var s = atob(b64), n = s.length, u = new Uint8Array(n);
  for (var i = 0; i < n; i++) u[i] = s.charCodeAt(i);
  return new T(u.buffer);
}
var N = D.times.length, NB = D.nbodies, poses = dec(D.poses, Float32Array);
var items = D.items.map(function (it) {
  var o = Object.assign({}, it);
  o.v = dec(it.v, Float32Array);
  o.faces = dec(it.faces, Int32Array);
  o.fcount = dec(it.fcount, Int32Array);
  o.upto = dec(it.upto, Int32Array);
  o.w = new Float64Array(it.nv * 3);
  o.s = new Float64Array(it.nv * 3);
  o.css = rgba(it.color, 1);
  o.ecss = it.edge ? rgba(it.edge, 1) : null;
  return o;
});

// ---- small vector helpers ------------------------------------------------------------
function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function scl(a, s) { return [a[0] * s, a[1] * s, a[2] * s]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function cross(a, b) {
  return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
}
function unit(a) { var l = Math.sqrt(dot(a, a)) || 1; return scl(a, 1 / l); }
function rgba(c, f) {
  return "rgba(" + Math.round(255 * Math.min(1, c[0] * f)) + "," + Math.round(255 * Math.min(1, c[1] * f)) +
    "," + Math.round(255 * Math.min(1, c[2] * f)) + "," + c[3] + ")";
}

// ---- camera --------------------------------------------------------------------------
var lo = D.bounds[0], hi = D.bounds[1], DEG = Math.PI / 180;
var center = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
var cam = {target: center.slice(), dist: 1, yaw: 0, pitch: 0, ortho: D.dim === 2, fov: 35 * DEG,
  up: D.dim === 2 ? [0, 1, 0] : [0, 0, 1], fwd: D.dim === 2 ? [0, 0, 1] : [1, 0, 0]};
var W = 1, H = 1, F = 1, E, R, U, V;

function basis() {
  var S = cross(cam.up, cam.fwd), cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
  var off = add(add(scl(cam.fwd, cp * Math.cos(cam.yaw)), scl(S, cp * Math.sin(cam.yaw))), scl(cam.up, sp));
  E = add(cam.target, scl(off, cam.dist));
  V = scl(off, -1);
  R = unit(cross(V, cam.up));
  U = cross(R, V);
  F = 0.5 * Math.min(W, H) / Math.tan(cam.fov / 2);
}
function fit() {
  cam.target = center.slice();
  cam.dist = 1;
  basis();
  var hx = 0, hy = 0, hz = 0;
  for (var c = 0; c < 8; c++) {
    var p = [c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]], d = sub(p, center);
    hx = Math.max(hx, Math.abs(dot(d, R)));
    hy = Math.max(hy, Math.abs(dot(d, U)));
    hz = Math.max(hz, Math.abs(dot(d, V)));
  }
  var dd = Math.max(F * hx / (0.46 * W), F * hy / (0.42 * H), 1e-9);
  cam.dist = cam.ortho ? dd : dd + 0.6 * hz;
  basis();
}
function home() {
  if (D.dim === 2) { cam.yaw = 0; cam.pitch = 0; } else { cam.yaw = -60 * DEG; cam.pitch = 25 * DEG; }
  cam.ortho = D.dim === 2;
  orthoBox.checked = cam.ortho;
  userView = false;
  fit();
  dirty = true;
}

// ---- placing and projecting ----------------------------------------------------------
function place(it, k) {
  var w = it.w, v = it.v, nv = it.nv, i;
  if (it.body >= 0) {
    var o = (k * NB + it.body) * 12, P = poses;
    var r0 = P[o], r1 = P[o + 1], r2 = P[o + 2];
    var a = P[o + 3], b = P[o + 4], c = P[o + 5], d = P[o + 6], e = P[o + 7], f = P[o + 8],
      g = P[o + 9], h = P[o + 10], m = P[o + 11];
    for (i = 0; i < nv; i++) {
      var x = v[3 * i], y = v[3 * i + 1], z = v[3 * i + 2];
      w[3 * i] = r0 + a * x + b * y + c * z;
      w[3 * i + 1] = r1 + d * x + e * y + f * z;
      w[3 * i + 2] = r2 + g * x + h * y + m * z;
    }
  } else {
    var base = (it.nf > 1 ? k : 0) * nv * 3;
    for (i = 0; i < 3 * nv; i++) w[i] = v[base + i];
  }
}
function project(it) {
  var w = it.w, s = it.s, nv = it.nv, near = 1e-3 * cam.dist;
  for (var i = 0; i < nv; i++) {
    var dx = w[3 * i] - E[0], dy = w[3 * i + 1] - E[1], dz = w[3 * i + 2] - E[2];
    var x = dx * R[0] + dy * R[1] + dz * R[2], y = dx * U[0] + dy * U[1] + dz * U[2],
      z = dx * V[0] + dy * V[1] + dz * V[2];
    var f = cam.ortho ? F / cam.dist : (z > near ? F / z : NaN);
    s[3 * i] = W / 2 + x * f; s[3 * i + 1] = H / 2 - y * f; s[3 * i + 2] = z;
  }
}
function fin(s, i) { return isFinite(s[3 * i]) && isFinite(s[3 * i + 1]); }

// ---- painting ------------------------------------------------------------------------
var canvas = document.getElementById("view"), ctx = canvas.getContext("2d");
// a fixed canvas size, from the data or the URL (viewer.html#size=800x500)
var fixed = D.size, m = /size=(\d+)x(\d+)/.exec(window.location.hash || "");
if (m) fixed = [parseInt(m[1], 10), parseInt(m[2], 10)];
if (fixed) { canvas.style.width = fixed[0] + "px"; canvas.style.height = fixed[1] + "px"; }
var frame = 0, dirty = true, userView = false;

function resize() {
  var dpr = window.devicePixelRatio || 1, w = canvas.clientWidth || 300, h = canvas.clientHeight || 150;
  if (w !== W || h !== H || canvas.width !== Math.round(w * dpr)) {
    W = w; H = h;
    canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return true;
  }
  return false;
}

function collect(k, list, texts) {
  var L = unit(add(add(scl(V, -1), scl(U, 0.55)), scl(R, -0.35)));
  for (var n = 0; n < items.length; n++) {
    var it = items[n];
    place(it, k); project(it);
    var s = it.s, w = it.w, nv = it.nv, i, j;
    if (it.upto) nv = Math.min(nv, it.upto[Math.min(k, it.upto.length - 1)]);
    if (it.kind === "mesh" || it.kind === "polygon") {
      var f0 = 0, nf = it.fcount.length;
      for (var fi = 0; fi < nf; fi++) {
        var cnt = it.fcount[fi], ok = true, depth = 0, nx = 0, ny = 0, nz = 0;
        for (j = 0; j < cnt; j++) {
          var a = it.faces[f0 + j], b = it.faces[f0 + (j + 1) % cnt];
          if (!fin(s, a)) { ok = false; break; }
          depth += s[3 * a + 2];
          nx += (w[3 * a + 1] - w[3 * b + 1]) * (w[3 * a + 2] + w[3 * b + 2]);
          ny += (w[3 * a + 2] - w[3 * b + 2]) * (w[3 * a] + w[3 * b]);
          nz += (w[3 * a] - w[3 * b]) * (w[3 * a + 1] + w[3 * b + 1]);
        }
        if (ok && cnt >= 3) {
          var shade = 1;
          if (D.dim === 3 && it.fill) {
            var nl = Math.sqrt(nx * nx + ny * ny + nz * nz) || 1;
            shade = 0.38 + 0.62 * Math.abs((nx * L[0] + ny * L[1] + nz * L[2]) / nl);
          }
          list.push({d: depth / cnt, layer: it.layer, t: 0, it: it, f0: f0, cnt: cnt, shade: shade});
        }
        f0 += cnt;
      }
    } else if (it.kind === "line") {
      var last = it.closed ? nv : nv - 1;
      for (i = 0; i < last; i++) {
        j = (i + 1) % nv;
        if (!(fin(s, i) && fin(s, j))) continue;
        // long segments are cut into pieces sorted on their own (better painter's order)
        var len = Math.hypot(s[3 * j] - s[3 * i], s[3 * j + 1] - s[3 * i + 1]);
        var pieces = D.dim === 3 ? Math.min(24, Math.max(1, Math.ceil(len / 25))) : 1;
        for (var q = 0; q < pieces; q++) {
          var u0 = q / pieces, u1 = (q + 1) / pieces, um = (u0 + u1) / 2;
          list.push({d: s[3 * i + 2] * (1 - um) + s[3 * j + 2] * um, layer: it.layer, t: 1, it: it,
            i: i, j: j, u0: u0, u1: u1});
        }
      }
    } else if (it.kind === "points") {
      for (i = 0; i < nv; i++) {
        if (fin(s, i)) list.push({d: s[3 * i + 2], layer: it.layer, t: 2, it: it, i: i});
      }
    } else if (it.kind === "text") {
      for (i = 0; i < nv; i++) if (fin(s, i)) texts.push({it: it, i: i});
    }
  }
}

function paint(p) {
  var it = p.it, s = it.s, j, idx;
  if (p.t === 0) {
    ctx.beginPath();
    for (j = 0; j < p.cnt; j++) {
      idx = it.faces[p.f0 + j];
      if (j === 0) ctx.moveTo(s[3 * idx], s[3 * idx + 1]); else ctx.lineTo(s[3 * idx], s[3 * idx + 1]);
    }
    ctx.closePath();
    ctx.setLineDash([]);
    if (it.fill) {
      var css = p.shade === 1 ? it.css : rgba(it.color, p.shade);
      ctx.fillStyle = css; ctx.fill();
      if (it.ecss && it.kind === "polygon") {
        ctx.strokeStyle = it.ecss; ctx.lineWidth = it.lw; ctx.stroke();
      } else if (it.color[3] >= 1) {
        ctx.strokeStyle = css; ctx.lineWidth = 0.6; ctx.stroke();  // hide seams between faces
      }
    } else { ctx.strokeStyle = it.css; ctx.lineWidth = it.lw; ctx.stroke(); }
  } else if (p.t === 1) {
    var xi = s[3 * p.i], yi = s[3 * p.i + 1], dx = s[3 * p.j] - xi, dy = s[3 * p.j + 1] - yi;
    ctx.beginPath();
    ctx.moveTo(xi + p.u0 * dx, yi + p.u0 * dy); ctx.lineTo(xi + p.u1 * dx, yi + p.u1 * dy);
    ctx.setLineDash(it.dash || []);
    ctx.strokeStyle = it.css; ctx.lineWidth = it.lw; ctx.lineCap = "round"; ctx.stroke();
  } else {
    ctx.beginPath();
    ctx.arc(s[3 * p.i], s[3 * p.i + 1], Math.max(it.ms / 2, 1), 0, 2 * Math.PI);
    ctx.setLineDash([]);
    if (it.hollow) { ctx.strokeStyle = it.css; ctx.lineWidth = 1.5; ctx.stroke(); }
    else { ctx.fillStyle = it.css; ctx.fill(); }
  }
}

function triad() {
  var ox = 42, oy = H - 42, len = 26, names = ["x", "y", "z"], cols = ["#d62728", "#2ca02c", "#1f77b4"];
  ctx.setLineDash([]); ctx.lineWidth = 2; ctx.font = "11px sans-serif";
  for (var a = 0; a < (D.dim === 2 ? 2 : 3); a++) {
    var e = [0, 0, 0]; e[a] = 1;
    var x = ox + len * dot(e, R), y = oy - len * dot(e, U);
    ctx.strokeStyle = cols[a]; ctx.fillStyle = cols[a];
    ctx.beginPath(); ctx.moveTo(ox, oy); ctx.lineTo(x, y); ctx.stroke();
    ctx.fillText(names[a], x + 3 * (x - ox) / len - 3, y + 3 * (y - oy) / len + 4);
  }
}

function render() {
  if (resize() && !userView) fit();
  basis();
  ctx.setTransform(window.devicePixelRatio || 1, 0, 0, window.devicePixelRatio || 1, 0, 0);
  ctx.fillStyle = "#ffffff"; ctx.fillRect(0, 0, W, H);
  var list = [], texts = [];
  collect(frame, list, texts);
  if (D.dim === 2) list.sort(function (a, b) { return (a.layer - b.layer) || (b.d - a.d); });
  else list.sort(function (a, b) { return (b.d - a.d) || (a.layer - b.layer); });
  ctx.lineJoin = "round";
  for (var n = 0; n < list.length; n++) paint(list[n]);
  for (n = 0; n < texts.length; n++) {
    var t = texts[n], s = t.it.s;
    ctx.fillStyle = t.it.css; ctx.font = t.it.fs + "px sans-serif";
    ctx.fillText(t.it.texts[t.i] || "", s[3 * t.i], s[3 * t.i + 1]);
  }
  triad();
  timeBox.textContent = D.label + " = " + D.times[frame].toFixed(3);
  probe();
}

function probe() {
  var out = [];
  for (var n = 0; n < items.length; n++) {
    var it = items[n];
    if (it.kind !== "mesh" && it.kind !== "polygon") continue;
    var sx = 0, sy = 0, c = 0, x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    for (var i = 0; i < it.nv; i++) {
      if (!fin(it.s, i)) continue;
      var x = it.s[3 * i], y = it.s[3 * i + 1];
      sx += x; sy += y; c++;
      x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y);
    }
    if (c) out.push({n: n, kind: it.kind, layer: it.layer, body: it.body, x: sx / c, y: sy / c,
      w: x1 - x0, h: y1 - y0});
  }
  canvas.setAttribute("data-probe", JSON.stringify({width: W, height: H, items: out}));
  canvas.setAttribute("data-ready", "1");
}

// ---- controls ------------------------------------------------------------------------
var slider = document.getElementById("slider"), playBtn = document.getElementById("play");
var rateSel = document.getElementById("rate"), orthoBox = document.getElementById("ortho");
var timeBox = document.getElementById("time");
document.getElementById("title").textContent = D.title;
document.title = D.title;
slider.max = String(N - 1);
var rates = [0.1, 0.25, 0.5, 1, 2, 4];
if (rates.indexOf(D.rate) < 0) { rates.push(D.rate); rates.sort(function (a, b) { return a - b; }); }
rates.forEach(function (r) {
  var o = document.createElement("option"); o.value = String(r); o.textContent = r + "x";
  if (r === D.rate) o.selected = true;
  rateSel.appendChild(o);
});
var t0 = D.times[0], t1 = D.times[N - 1], simT = t0, playing = false, lastTs = null;
if (N < 2) { playBtn.disabled = true; slider.disabled = true; }
function setPlaying(p) {
  playing = p && N > 1;
  playBtn.innerHTML = playing ? "&#10074;&#10074;" : "&#9654;";
  lastTs = null;
}
function frameAt(t) {
  var a = 0, b = N - 1;
  while (a < b) { var m = (a + b + 1) >> 1; if (D.times[m] <= t + 1e-12) a = m; else b = m - 1; }
  return a;
}
function show(k) {
  frame = Math.max(0, Math.min(N - 1, k));
  slider.value = String(frame);
  simT = D.times[frame];
  dirty = true;
}
playBtn.addEventListener("click", function () {
  if (!playing && frame === N - 1) show(0);
  setPlaying(!playing);
});
slider.addEventListener("input", function () { setPlaying(false); show(parseInt(slider.value, 10)); });
orthoBox.addEventListener("change", function () { cam.ortho = orthoBox.checked; fit(); dirty = true; });
document.getElementById("home").addEventListener("click", home);
window.addEventListener("keydown", function (e) {
  if (e.target && e.target.tagName === "SELECT") return;
  if (e.key === " ") { e.preventDefault(); setPlaying(!playing); }
  else if (e.key === "ArrowRight") { setPlaying(false); show(frame + 1); }
  else if (e.key === "ArrowLeft") { setPlaying(false); show(frame - 1); }
  else if (e.key === "r") home();
});
var drag = null;
canvas.addEventListener("pointerdown", function (e) {
  drag = {x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey || e.button === 1};
  canvas.setPointerCapture(e.pointerId); canvas.classList.add("drag");
});
canvas.addEventListener("pointermove", function (e) {
  if (!drag) return;
  var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag.x = e.clientX; drag.y = e.clientY;
  userView = true;
  if (drag.pan) {
    var upp = cam.dist / F;
    cam.target = add(cam.target, add(scl(R, -dx * upp), scl(U, dy * upp)));
  } else {
    cam.yaw -= dx * 0.008;
    cam.pitch = Math.max(-1.55, Math.min(1.55, cam.pitch + dy * 0.008));
  }
  dirty = true;
});
function endDrag() { drag = null; canvas.classList.remove("drag"); }
canvas.addEventListener("pointerup", endDrag);
canvas.addEventListener("pointercancel", endDrag);
canvas.addEventListener("contextmenu", function (e) { e.preventDefault(); });
canvas.addEventListener("dblclick", home);
canvas.addEventListener("wheel", function (e) {
  e.preventDefault();
  cam.dist *= Math.exp(Math.max(-1, Math.min(1, e.deltaY * 0.0015)));
  userView = true;
  dirty = true;
}, {passive: false});
window.addEventListener("resize", function () { dirty = true; });

function tick(ts) {
  if (playing) {
    if (lastTs !== null) {
      simT += (ts - lastTs) / 1000 * parseFloat(rateSel.value);
      if (simT > t1) simT = t0 + ((simT - t1) % Math.max(t1 - t0, 1e-12));
      var k = frameAt(simT);
      if (k !== frame) { frame = k; slider.value = String(k); dirty = true; }
    }
    lastTs = ts;
  }
  if (dirty) { dirty = false; render(); }
  window.requestAnimationFrame(tick);
}

resize();
home();
render();
dirty = false;
setPlaying(D.autoplay);
window.requestAnimationFrame(tick);
window.mechsysViewer = {data: D, camera: cam, show: show, render: render};
})();
"""
