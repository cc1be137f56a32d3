// The page of `dpc dashboard`: snapshots arrive over a WebSocket (/ws) a few tens of times a
// second; the sphere is drawn every animation frame; the plots keep the last minute.
import * as THREE from './vendor/three/three.module.js';
import uPlot from './vendor/uplot/uPlot.esm.js';

const HISTORY_S = 60;
const TRAIL_POINTS = 600;
const css = getComputedStyle(document.documentElement);
const color = (name) => css.getPropertyValue(name).trim();
const $ = (id) => document.getElementById(id);

// What tests (and curious users, in the console) can read.
const state = {
  snapshots: 0, frames: 0, fps: 0, condition: 'WAITING', sOut: null, targetRevision: null,
  lastAnswer: null, connected: false, errorPoints: 0, webglLost: false,
};
window.dpcDashboard = state;

// ---------------------------------------------------------------- the Poincaré sphere
// Stokes (S1, S2, S3) → three.js (x, y, z) = (S1, S3, −S2): S3 up, right-handed.
const toScene = (s) => new THREE.Vector3(s[0], s[2], -s[1]);

// A software rasterizer (SwiftShader, llvmpipe: headless browsers, machines without a GPU) draws
// multisampled frames at a few per second: it gets no antialiasing and one pixel per CSS pixel.
function softwareRenderer() {
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
    const name = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : '';
    gl?.getExtension('WEBGL_lose_context')?.loseContext();
    return /swiftshader|llvmpipe|software/i.test(name);
  } catch { return false; }
}
const software = softwareRenderer();
state.softwareRendering = software;
const canvas = $('sphere');
// preserveDrawingBuffer: the canvas can be read back (tests check that it is drawn).
const renderer = new THREE.WebGLRenderer({ canvas, antialias: !software, preserveDrawingBuffer: true });
renderer.setPixelRatio(software ? 1 : Math.min(window.devicePixelRatio || 1, 2));
renderer.setClearColor(color('--panel'));
canvas.addEventListener('webglcontextlost', () => { state.webglLost = true; });
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(35, 1, 0.1, 100);
const view = { azimuth: 0.9, elevation: 0.4, distance: 5.0 };
let needsRender = true;  // drawn only when something changed: data, view or size

function placeCamera() {
  const { azimuth, elevation, distance } = view;
  camera.position.set(distance * Math.cos(elevation) * Math.sin(azimuth), distance * Math.sin(elevation),
    distance * Math.cos(elevation) * Math.cos(azimuth));
  camera.lookAt(0, 0, 0);
}

function circlePoints(center, u, v, radius, n = 96) {
  const points = [];
  for (let i = 0; i <= n; i++) {
    const a = (2 * Math.PI * i) / n;
    points.push(center.clone().addScaledVector(u, radius * Math.cos(a)).addScaledVector(v, radius * Math.sin(a)));
  }
  return points;
}

function buildSphere() {
  scene.add(new THREE.Mesh(new THREE.SphereGeometry(1, 48, 32),
    new THREE.MeshBasicMaterial({ color: 0x3a4a60, transparent: true, opacity: 0.25, depthWrite: false })));
  const grid = new THREE.LineBasicMaterial({ color: 0x3d4757 });
  const strong = new THREE.LineBasicMaterial({ color: 0x6b7890 });
  const X = new THREE.Vector3(1, 0, 0), Y = new THREE.Vector3(0, 1, 0), Z = new THREE.Vector3(0, 0, 1);
  for (let lat = -60; lat <= 60; lat += 30) {  // parallels (S3 constant)
    const r = Math.cos((lat * Math.PI) / 180);
    const c = new THREE.Vector3(0, Math.sin((lat * Math.PI) / 180), 0);
    scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(circlePoints(c, X, Z, r)), lat === 0 ? strong : grid));
  }
  for (let lon = 0; lon < 180; lon += 30) {  // meridians
    const a = (lon * Math.PI) / 180;
    const u = new THREE.Vector3(Math.cos(a), 0, Math.sin(a));
    scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(circlePoints(new THREE.Vector3(), u, Y, 1)),
      lon % 90 === 0 ? strong : grid));
  }
  const axes = [['S1', [1, 0, 0]], ['S2', [0, 1, 0]], ['S3', [0, 0, 1]]];
  for (const [name, s] of axes) {
    const tip = toScene(s).multiplyScalar(1.3);
    scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints([tip.clone().negate(), tip]),
      new THREE.LineBasicMaterial({ color: 0x9aa5b8 })));
    scene.add(label(name, tip.clone().multiplyScalar(1.1)));
  }
}

function label(text, position) {
  const c = document.createElement('canvas');
  c.width = 128; c.height = 64;
  const g = c.getContext('2d');
  g.fillStyle = '#d8dee9';
  g.font = 'bold 40px sans-serif';
  g.textAlign = 'center'; g.textBaseline = 'middle';
  g.fillText(text, 64, 32);
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(c), depthTest: false }));
  sprite.position.copy(position);
  sprite.scale.set(0.36, 0.18, 1);
  return sprite;
}

function marker(hex, radius = 0.045) {
  // Drawn after the translucent sphere (transparent pass, later order): never tinted by it.
  const m = new THREE.Mesh(new THREE.SphereGeometry(radius, 20, 14),
    new THREE.MeshBasicMaterial({ color: hex, transparent: true, opacity: 1 }));
  m.renderOrder = 2;
  m.visible = false;
  scene.add(m);
  return m;
}

// A trail: the latest TRAIL_POINTS positions, fading into the background.
class Trail {
  constructor(hex) {
    this.points = [];
    this.color = new THREE.Color(hex);
    this.background = new THREE.Color(color('--panel'));
    this.geometry = new THREE.BufferGeometry();
    this.positions = new Float32Array(TRAIL_POINTS * 3);
    this.colors = new Float32Array(TRAIL_POINTS * 3);
    this.geometry.setAttribute('position', new THREE.BufferAttribute(this.positions, 3));
    this.geometry.setAttribute('color', new THREE.BufferAttribute(this.colors, 3));
    this.line = new THREE.Line(this.geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
    this.line.frustumCulled = false;
    scene.add(this.line);
  }
  push(s) {
    this.points.push(toScene(s).multiplyScalar(1.004));
    if (this.points.length > TRAIL_POINTS) this.points.splice(0, this.points.length - TRAIL_POINTS);
    this.dirty = true;
  }
  update() {
    if (!this.dirty) return;
    this.dirty = false;
    const n = this.points.length;
    const c = new THREE.Color();
    for (let i = 0; i < n; i++) {
      const p = this.points[i];
      this.positions.set([p.x, p.y, p.z], 3 * i);
      c.copy(this.background).lerp(this.color, 0.15 + 0.85 * (i / Math.max(1, n - 1)));
      this.colors.set([c.r, c.g, c.b], 3 * i);
    }
    this.geometry.setDrawRange(0, n);
    this.geometry.attributes.position.needsUpdate = true;
    this.geometry.attributes.color.needsUpdate = true;
  }
}

buildSphere();
const sInMarker = marker(color('--s-in'));
const sOutMarker = marker(color('--s-out'), 0.055);
const targetMarker = marker(color('--target'), 0.06);
const targetCircle = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: color('--target') }));
targetCircle.visible = false;
scene.add(targetCircle);
const trailIn = new Trail(color('--s-in'));
const trailOut = new Trail(color('--s-out'));
let targetKey = '';

function showTarget(target) {
  const key = JSON.stringify(target);
  if (key === targetKey) return;
  targetKey = key;
  targetMarker.visible = false;
  targetCircle.visible = false;
  if (!target) return;
  if (target.kind === 'point') {
    targetMarker.position.copy(toScene(target.point));
    targetMarker.visible = true;
  } else {
    // The circle n·S = c: centre c·n, radius √(1 − c²), in the plane normal to n.
    const n = toScene(target.normal).normalize();
    const c = target.offset;
    const u = new THREE.Vector3().crossVectors(n, Math.abs(n.y) < 0.9 ? new THREE.Vector3(0, 1, 0) : new THREE.Vector3(1, 0, 0)).normalize();
    const v = new THREE.Vector3().crossVectors(n, u);
    const points = circlePoints(n.clone().multiplyScalar(c), u, v, Math.sqrt(Math.max(0, 1 - c * c)) * 1.004, 128);
    targetCircle.geometry.dispose();
    targetCircle.geometry = new THREE.BufferGeometry().setFromPoints(points);
    targetCircle.visible = true;
  }
}

// Drag to rotate, wheel to zoom.
let drag = null;
canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY }; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener('pointerup', () => { drag = null; });
canvas.addEventListener('pointermove', (e) => {
  if (!drag) return;
  view.azimuth -= (e.clientX - drag.x) * 0.008;
  view.elevation = Math.max(-1.5, Math.min(1.5, view.elevation + (e.clientY - drag.y) * 0.008));
  drag = { x: e.clientX, y: e.clientY };
  needsRender = true;
});
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  view.distance = Math.max(2.2, Math.min(12, view.distance * Math.exp(e.deltaY * 0.001)));
  needsRender = true;
}, { passive: false });

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
    needsRender = true;
  }
}

// state.fps: animation frames per second (how smoothly the page runs); state.drawsPerS: sphere
// redraws per second (at most one per frame, one per snapshot while the view is still).
let fpsFrames = 0, fpsDraws = 0, fpsSince = performance.now();
state.draws = 0;
function frame(now) {
  resize();
  if (needsRender) {
    needsRender = false;
    placeCamera();
    trailIn.update();
    trailOut.update();
    renderer.render(scene, camera);
    state.draws++;
    fpsDraws++;
  }
  drawPanels(now);
  state.frames++;
  fpsFrames++;
  if (now - fpsSince >= 1000) {
    state.fps = (1000 * fpsFrames) / (now - fpsSince);
    state.drawsPerS = (1000 * fpsDraws) / (now - fpsSince);
    fpsFrames = 0; fpsDraws = 0; fpsSince = now;
    $('fps').textContent = `${state.fps.toFixed(0)} fps, ${state.drawsPerS.toFixed(0)} draws/s`;
  }
  requestAnimationFrame(frame);
}
requestAnimationFrame(frame);

// ---------------------------------------------------------------- plots
function plotWidth(id) { return Math.max(300, $(id).clientWidth); }

const errorData = [[], [], [], [], []];  // t, mean error, max error, threshold, extinction
const errorPlot = new uPlot({
  width: plotWidth('error-plot'), height: 200, legend: { live: false },
  scales: { x: { time: false }, deg: { range: (u, min, max) => [0, Math.max(5, max * 1.1)] }, db: { range: [-80, 0] } },
  axes: [
    { label: 's', stroke: color('--muted'), grid: { stroke: '#2c3542' } },
    { scale: 'deg', label: 'error (deg)', stroke: color('--muted'), grid: { stroke: '#2c3542' } },
    { scale: 'db', side: 1, label: 'extinction (dB)', stroke: color('--muted'), grid: { show: false } },
  ],
  series: [
    { label: 't (s)' },
    { label: 'mean error (deg)', scale: 'deg', stroke: color('--s-out'), width: 1.5 },
    { label: 'max error (deg)', scale: 'deg', stroke: '#a0623a', width: 1 },
    { label: 'lock threshold (deg)', scale: 'deg', stroke: color('--target'), dash: [6, 4], width: 1 },
    { label: 'extinction (dB)', scale: 'db', stroke: '#b38cff', width: 1 },
  ],
}, errorData, $('error-plot'));

let phiPlot = null;
let phiData = null;
const phiColors = ['#ff9f43', '#4ea1ff', '#2ecc71', '#e056fd', '#f1c40f', '#00d2d3', '#ff6b6b', '#c8d6e5'];

function ensurePhiPlot(count) {
  if (phiPlot && phiData.length === count + 1) return;
  if (phiPlot) phiPlot.destroy();
  phiData = Array.from({ length: count + 1 }, () => []);
  const series = [{ label: 't (s)' }];
  for (let i = 0; i < count; i++) series.push({ label: `φ${i + 1}`, stroke: phiColors[i % phiColors.length], width: 1.2 });
  phiPlot = new uPlot({
    width: plotWidth('phi-plot'), height: 170, legend: { live: false },
    scales: { x: { time: false } },
    axes: [{ stroke: color('--muted'), grid: { stroke: '#2c3542' } }, { label: 'φ', stroke: color('--muted'), grid: { stroke: '#2c3542' } }],
    series,
  }, phiData, $('phi-plot'));
}

function trim(data, now) {
  let drop = 0;
  while (drop < data[0].length && data[0][drop] < now - HISTORY_S) drop++;
  if (drop > 0) for (const column of data) column.splice(0, drop);
}

window.addEventListener('resize', () => {
  errorPlot.setSize({ width: plotWidth('error-plot'), height: 200 });
  if (phiPlot) phiPlot.setSize({ width: plotWidth('phi-plot'), height: 170 });
});

// ---------------------------------------------------------------- panels
const fmt = (x, digits = 2) => (x === null || x === undefined || !Number.isFinite(x) ? '—' : x.toFixed(digits));

function duration(s) {
  if (s < 60) return `${s.toFixed(1)} s`;
  if (s < 3600) return `${Math.floor(s / 60)} min ${Math.floor(s % 60)} s`;
  return `${Math.floor(s / 3600)} h ${Math.floor((s % 3600) / 60)} min`;
}

function showBadge(condition, forS) {
  const badge = $('badge');
  badge.textContent = condition;
  badge.dataset.condition = condition;
  badge.className = `badge ${condition.toLowerCase().replace(/\s/g, '')}`;
  $('badge-since').textContent = forS === null ? '' : `for ${duration(forS)}`;
  state.condition = condition;
}

let phiScale = 1;  // for stages without a range: grows by doubling, never shrinks
function showPhiBars(snapshot) {
  const driver = snapshot.driver;
  const bars = $('phi-bars');
  if (!driver) { bars.textContent = 'no state from the driver yet'; return; }
  const stages = snapshot.device ? snapshot.device.stages : [];
  for (const phi of driver.phi) {
    while (Math.abs(phi) > phiScale) phiScale *= 2;
  }
  if (bars.childElementCount !== 3 * driver.phi.length) {
    bars.textContent = '';
    driver.phi.forEach((_, i) => {
      const name = document.createElement('div'); name.textContent = `φ${i + 1}`;
      const track = document.createElement('div'); track.className = 'phi-track';
      const zero = document.createElement('div'); zero.className = 'phi-zero'; track.append(zero);
      const mark = document.createElement('div'); mark.className = 'phi-mark'; track.append(mark);
      const value = document.createElement('div'); value.className = 'phi-value';
      bars.append(name, track, value);
    });
  }
  driver.phi.forEach((phi, i) => {
    const track = bars.children[3 * i + 1];
    const stage = stages[i] || {};
    // The stage's range, else a scale shared by the stages: ±(largest |φ| seen, rounded up).
    const min = stage.min ?? -phiScale, max = stage.max ?? phiScale;
    const at = (x) => `${(100 * (Math.min(max, Math.max(min, x)) - min)) / (max - min)}%`;
    track.children[0].style.left = at(0);
    track.children[1].style.left = at(phi);
    track.children[1].classList.toggle('saturated', !!driver.saturated[i]);
    track.title = `range [${min}, ${max}]${driver.saturated[i] ? ', saturated' : ''}`;
    bars.children[3 * i + 2].textContent = `${phi.toFixed(3)}${driver.saturated[i] ? ' ⚠' : ''}`;
  });
}

function cell(text) { const td = document.createElement('td'); td.textContent = text; return td; }

function showDriver(snapshot) {
  const d = snapshot.driver;
  $('driver-mode').textContent = d ? d.mode : '—';
  $('driver-reason').textContent = d ? (d.reason || '—') : '—';
  $('driver-obeyed').textContent = d && d.obeyed_id ? `${d.obeyed_id} (priority ${d.obeyed_priority})` : '—';
  $('driver-switches').textContent = d ? String(d.controller_switches) : '—';
  $('driver-commands').textContent = d ? `${d.commands_applied} applied, ${d.commands_limited} limited, ${d.commands_rejected} refused` : '—';
  const t = snapshot.target;
  $('target-now').textContent = !t ? '—'
    : (t.kind === 'point' ? `point [${t.point.map((x) => x.toFixed(3)).join(', ')}]`
      : `set [${t.normal.map((x) => x.toFixed(3)).join(', ')}]·S = ${t.offset.toFixed(3)}`) + `, revision ${t.revision_count}`;
  const body = $('controllers').tBodies[0];
  body.textContent = '';
  for (const c of snapshot.controllers) {
    const row = document.createElement('tr');
    if (c.obeyed) row.className = 'obeyed';
    else if (c.silent_s > 2) row.className = 'silent';
    row.append(cell(c.id), cell(String(c.priority)), cell(c.law),
      cell(c.silent_s > 2 ? `silent for ${duration(c.silent_s)}` : c.condition),
      cell(fmt(c.sigma_min, 3)), cell(`${fmt(c.compute_mean_us, 1)} / ${fmt(c.compute_max_us, 1)}`),
      cell(String(c.missed_deadlines)));
    body.append(row);
  }
  if (snapshot.controllers.length === 0) {
    const row = document.createElement('tr');
    const td = cell('no controller status seen'); td.colSpan = 7; row.append(td); body.append(row);
  }
}

// Snapshots only store; the plots and panels are redrawn at most PANEL_HZ times a second (in the
// animation frame), the sphere at every snapshot: the page's work does not grow with --push-hz.
const PANEL_HZ = 5;
let plotsStale = false;
let latest = null;
let panelsDrawnAt = 0;
function drawPanels(now) {
  if (now - panelsDrawnAt < 1000 / PANEL_HZ) return;
  panelsDrawnAt = now;
  if (plotsStale) {
    plotsStale = false;
    errorPlot.setData(errorData);
    if (phiPlot) phiPlot.setData(phiData);
  }
  if (latest) {
    showPhiBars(latest);
    showDriver(latest);
    latest = null;
  }
}

function onSnapshot(s) {
  state.snapshots++;
  needsRender = true;
  $('bench-id').textContent = s.bench_id;
  document.title = `DPC bench ${s.bench_id}: ${s.condition}`;
  showBadge(s.condition, s.condition_for_s);
  $('rate').textContent = `${fmt(s.samples.rate_hz, 0)} Hz`;
  const l = s.loop_latency_us;
  $('latency').textContent = l ? `loop p50 ${l.p50.toFixed(0)} µs, p99 ${l.p99.toFixed(0)} µs` : 'loop —';
  for (const p of s.trail.s_in) trailIn.push(p);
  for (const p of s.trail.s_out) trailOut.push(p);
  if (s.s_in) { sInMarker.position.copy(toScene(s.s_in)); sInMarker.visible = true; }
  if (s.s_out) { sOutMarker.position.copy(toScene(s.s_out)); sOutMarker.visible = true; state.sOut = s.s_out; }
  showTarget(s.target);
  state.targetRevision = s.target ? s.target.revision : null;  // text: 64 bits
  state.targetRevisionCount = s.target ? s.target.revision_count : null;

  // Plotted only when a summary of the bench arrived since the last snapshot.
  if (s.fresh && s.error_deg) {
    errorData[0].push(s.t_s); errorData[1].push(s.error_deg.mean); errorData[2].push(s.error_deg.max);
    errorData[3].push(s.lock_threshold_deg); errorData[4].push(Math.max(-80, Math.min(0, s.extinction_db)));
    trim(errorData, s.t_s);
    plotsStale = true;
    state.errorPoints = errorData[0].length;
    $('error-now').textContent = `mean ${s.error_deg.mean.toFixed(2)}°, max ${s.error_deg.max.toFixed(2)}°, extinction ${s.extinction_db.toFixed(1)} dB`;
  }
  if (s.fresh && s.driver) {
    ensurePhiPlot(s.driver.phi.length);
    phiData[0].push(s.t_s);
    s.driver.phi.forEach((phi, i) => phiData[i + 1].push(phi));
    trim(phiData, s.t_s);
    plotsStale = true;
  }
  latest = s;
  $('target-send').disabled = !!s.read_only;
  if (s.read_only) $('target-answer').textContent = 'read-only: this dashboard may not publish target requests';
}

function onAnswer(a) {
  state.lastAnswer = a;
  const answer = $('target-answer');
  answer.className = a.accepted ? 'accepted' : 'refused';
  answer.textContent = a.accepted ? `accepted: revision ${a.revision_count} (request ${a.request_id})` : `refused: ${a.message}`;
  $('target-send').disabled = false;
}

// ---------------------------------------------------------------- the connection
let socket = null;
let retryMs = 500;
function connect() {
  socket = new WebSocket(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`);
  socket.onopen = () => {
    retryMs = 500; state.connected = true;
    $('connection').textContent = 'connected'; $('connection').className = 'connection up';
  };
  socket.onmessage = (event) => {
    let message;
    try { message = JSON.parse(event.data); } catch { return; }
    if (message.type === 'snapshot') onSnapshot(message);
    else if (message.type === 'target_reply') onAnswer(message);
  };
  socket.onclose = () => {
    state.connected = false;
    $('connection').textContent = 'dpc dashboard unreachable, retrying…'; $('connection').className = 'connection down';
    showBadge('DISCONNECTED', null);
    setTimeout(connect, retryMs);
    retryMs = Math.min(5000, retryMs * 2);
  };
}
connect();

// ---------------------------------------------------------------- setting the target
let tagCount = 0;
const form = $('target-form');
form.addEventListener('change', () => {
  const kind = form.elements.kind.value;
  $('point-row').hidden = kind !== 'point';
  $('set-row').hidden = kind !== 'set';
});
form.addEventListener('submit', (event) => {
  event.preventDefault();
  const kind = form.elements.kind.value;
  const number = (id) => Number($(id).value.trim().replace(',', '.'));
  const request = { type: 'set_target', tag: `page-${++tagCount}`, kind };
  if (kind === 'point') request.point = ['p1', 'p2', 'p3'].map(number);
  if (kind === 'set') { request.normal = ['n1', 'n2', 'n3'].map(number); request.offset = number('offset'); }
  if (!socket || socket.readyState !== WebSocket.OPEN) {
    onAnswer({ accepted: false, message: 'not connected to dpc dashboard' });
    return;
  }
  socket.send(JSON.stringify(request));
  $('target-send').disabled = true;
  $('target-answer').className = 'muted';
  $('target-answer').textContent = 'sent, waiting for the driver…';
});
