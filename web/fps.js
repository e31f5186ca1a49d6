'use strict';
// The fps page: the focal plane drawn from the layout (/api/fps/info) with every robot's arms at
// their live angles and its state, pushed by the server (/ws?source=fps, docs/dashboard.md).
// window.axonFps holds what the page shows (info, state, what was drawn) for scripts and tests.
// A plan file (`axon fps plan -o plan.json`) can be loaded and replayed: while it is, the plane is
// drawn from the plan's trajectories at the replay's time instead of from the live state.

const STATE_COLOURS = {
  'ready': '#2e7d32',
  'moving': '#1565c0',
  'not-initialised': '#f9a825',
  'collided': '#c62828',
  'offline': '#9e9e9e',
  'bootloader': '#6a1b9a',
};

const fps = {
  info: null,       // layout, status bits, state names
  state: null,      // the latest state message
  seq: 0,           // its sequence number
  messages: 0,      // state messages received
  // What the canvas shows: the state's seq, robots drawn, 'live' or 'replay', the replay's time
  // (null when live) and every drawn robot's [id, alpha, beta] in degrees.
  drawn: { seq: 0, robots: 0, source: 'live', t: null, angles: [] },
  selected: null,   // id of the robot whose details are shown
  replay: {
    active: false,  // drawing from the plan, not from the live state
    file: null,     // name of the loaded plan file
    layout: null,   // the plan's layout name
    duration: 0,    // s: the latest last point of any arm (or the plan's duration_s if later)
    t: 0,           // s: the replay's time
    playing: false,
    speed: 1,       // plan seconds per wall-clock second
    robots: [],     // the plan's robots that are in the layout: {id, status, alpha, beta} ([deg, s] points)
    missing: [],    // ids of the plan's robots that are not in the layout (not drawn)
    absent: [],     // ids of layout robots the plan does not have (not drawn while replaying)
  },
};
window.axonFps = fps;

const sites = new Map();  // id -> robot of info
let view = null;          // plane -> canvas transform
let drawPending = false;

const $ = (id) => document.getElementById(id);

async function start() {
  const response = await fetch('/api/fps/info');
  fps.info = await response.json();
  for (const r of fps.info.robots) sites.set(r.id, r);
  // The host's view (axon fps plane --http: what the replies say) or the simulator's truth.
  const kind = fps.info.view === 'host' ? 'host view' : 'simulator';
  $('title').textContent = `${fps.info.layout}, ${fps.info.robots.length} robots (${kind})`;
  document.title = `axon fps: ${kind}`;
  buildLegend();
  $('plane').addEventListener('click', onClick);
  setUpReplay();
  window.addEventListener('resize', scheduleDraw);
  connect();
}

function buildLegend() {
  const legend = $('legend');
  for (const name of fps.info.states) {
    const li = document.createElement('li');
    li.innerHTML = `<span class="swatch" style="background:${STATE_COLOURS[name] || '#000'}"></span>` +
                   `<span>${name}</span> <span id="count-${name}">0</span>`;
    legend.appendChild(li);
  }
}

function connect() {
  axonConnect('fps', (message) => {
    fps.state = message.state;
    fps.seq = message.seq;
    fps.messages++;
    showSummary();
    showLock();
    showDetails();
    scheduleDraw();
  });
}

function showSummary() {
  const s = fps.state;
  $('robot-count').textContent = s.robots.length;
  $('moving-count').textContent = s.moving;
  for (const name of fps.info.states) {
    const el = $(`count-${name}`);
    if (el) el.textContent = s.states[name] || 0;
  }
  const atRest = s.robots.length ? 100 * (s.robots.length - s.moving) / s.robots.length : 100;
  $('progress').firstElementChild.style.width = `${atRest}%`;
}

function showLock() {
  const lock = fps.state.lock;
  const el = $('lock');
  el.className = lock.locked ? 'locked' : 'unlocked';
  el.dataset.locked = String(lock.locked);
  el.dataset.robot = lock.locked ? String(lock.robot) : '';
  if (!lock.locked) {
    el.textContent = lock.count ? `no collision (${lock.count} lock${lock.count > 1 ? 's' : ''} so far)` : 'no collision';
    return;
  }
  const others = lock.collided.filter((id) => id !== lock.robot);
  if (!lock.robot) {  // the host's lock after a stop without a collision: its reason
    el.textContent = `LOCKED: ${lock.reason || 'every robot stopped'}`;
    return;
  }
  el.textContent = `LOCKED: robot ${lock.robot} (${lock.bus}, ${lock.arm} arm) collided` +
                   (others.length ? `; also collided: ${others.join(', ')}` : '');
}

function scheduleDraw() {
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(() => { drawPending = false; draw(); });
}

// Plane millimetres (y up) to canvas pixels, fitted to the layout's extent.
function fitView(canvas) {
  const reach = 25;
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const r of fps.info.robots) {
    x0 = Math.min(x0, r.x - reach); x1 = Math.max(x1, r.x + reach);
    y0 = Math.min(y0, r.y - reach); y1 = Math.max(y1, r.y + reach);
  }
  for (const f of fps.info.fiducials) {
    x0 = Math.min(x0, f.x - 5); x1 = Math.max(x1, f.x + 5);
    y0 = Math.min(y0, f.y - 5); y1 = Math.max(y1, f.y + 5);
  }
  const scale = Math.min(canvas.width / (x1 - x0), canvas.height / (y1 - y0));
  const ox = (canvas.width - scale * (x1 - x0)) / 2 - scale * x0;
  const oy = (canvas.height - scale * (y1 - y0)) / 2 + scale * y1;
  return { scale, px: (x) => ox + scale * x, py: (y) => oy - scale * y, mmx: (px) => (px - ox) / scale, mmy: (py) => (oy - py) / scale };
}

function draw() {
  const canvas = $('plane');
  const ratio = window.devicePixelRatio || 1;
  const w = Math.round(canvas.clientWidth * ratio), h = Math.round(canvas.clientHeight * ratio);
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  if (!fps.info) return;
  const replay = fps.replay;
  if (replay.active) {
    const robots = replayPoses(replay.t);
    drawPlane(canvas, robots, null);
    $('replay-moving').textContent = robots.filter((r) => r.s === 'moving').length;
    fps.drawn = { seq: fps.seq, robots: robots.length, source: 'replay', t: replay.t, angles: robots.map((r) => [r.id, r.a, r.b]) };
  } else if (fps.state) {
    const robots = fps.state.robots.filter((r) => sites.has(r.id));
    drawPlane(canvas, robots, fps.state.lock);
    fps.drawn = { seq: fps.seq, robots: robots.length, source: 'live', t: null, angles: robots.map((r) => [r.id, r.a, r.b]) };
  }
}

// The one drawing of the plane, live or replayed: `robots` are {id, a, b, s} (alpha and beta in
// degrees, a state name for the colour), all in the layout; `lock` the live lock or null.
function drawPlane(canvas, robots, lock) {
  view = fitView(canvas);
  const ctx = canvas.getContext('2d');
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  drawFiducials(ctx);
  for (const robot of robots) drawRobot(ctx, sites.get(robot.id), robot, lock);
}

function drawFiducials(ctx) {
  const s = view.scale;
  ctx.strokeStyle = '#8d6e63';
  ctx.lineWidth = Math.max(1.5, 0.6 * s);
  for (const f of fps.info.fiducials) {
    const x = view.px(f.x), y = view.py(f.y), d = Math.max(4, 3 * s);
    ctx.beginPath();
    ctx.moveTo(x - d, y); ctx.lineTo(x + d, y);
    ctx.moveTo(x, y - d); ctx.lineTo(x, y + d);
    ctx.stroke();
  }
}

function drawRobot(ctx, site, robot, lock) {
  const s = view.scale, rad = Math.PI / 180;
  if (robot.a === null || robot.b === null) {  // the host has not read its position: its base only
    ctx.fillStyle = STATE_COLOURS[robot.s] || '#000';
    ctx.beginPath();
    ctx.arc(view.px(site.x), view.py(site.y), Math.max(1.5, 1.8 * s), 0, 2 * Math.PI);
    ctx.fill();
    return;
  }
  const a = (site.orientation + robot.a) * rad, b = a + robot.b * rad;
  const bx = site.x, by = site.y;
  const ax = bx + site.alpha_mm * Math.cos(a), ay = by + site.alpha_mm * Math.sin(a);
  const tx = ax + site.beta_mm * Math.cos(b), ty = ay + site.beta_mm * Math.sin(b);
  const colour = STATE_COLOURS[robot.s] || '#000';
  // The patrol disc, the alpha arm, the beta arm (the fibre end at its tip).
  ctx.beginPath();
  ctx.arc(view.px(bx), view.py(by), (site.alpha_mm + site.beta_mm) * s, 0, 2 * Math.PI);
  ctx.strokeStyle = '#eceff1';
  ctx.lineWidth = 1;
  ctx.stroke();
  ctx.lineCap = 'round';
  ctx.strokeStyle = '#90a4ae';
  ctx.lineWidth = Math.max(1, 1.2 * s);
  ctx.beginPath();
  ctx.moveTo(view.px(bx), view.py(by)); ctx.lineTo(view.px(ax), view.py(ay));
  ctx.stroke();
  ctx.strokeStyle = colour;
  ctx.lineWidth = Math.max(1.5, 2 * s);
  ctx.beginPath();
  ctx.moveTo(view.px(ax), view.py(ay)); ctx.lineTo(view.px(tx), view.py(ty));
  ctx.stroke();
  ctx.fillStyle = colour;
  ctx.beginPath();
  ctx.arc(view.px(bx), view.py(by), Math.max(1.5, 1.8 * s), 0, 2 * Math.PI);
  ctx.fill();
  const cause = lock !== null && lock.locked && lock.robot === robot.id;
  if (cause || robot.id === fps.selected) {
    ctx.beginPath();
    ctx.arc(view.px(bx), view.py(by), (site.alpha_mm + site.beta_mm + 1) * s, 0, 2 * Math.PI);
    ctx.strokeStyle = cause ? STATE_COLOURS.collided : '#000';
    ctx.lineWidth = cause ? 3 : 2;
    ctx.stroke();
  }
}

// Where robot `id`'s base is on the canvas, in CSS pixels from its top-left corner (for scripts).
fps.robotOnCanvas = (id) => {
  const site = sites.get(id);
  const canvas = $('plane');
  if (!site || !view) return null;
  const ratio = canvas.width / canvas.getBoundingClientRect().width;
  return { x: view.px(site.x) / ratio, y: view.py(site.y) / ratio };
};

function onClick(event) {
  if (!view) return;
  const canvas = $('plane');
  const rect = canvas.getBoundingClientRect();
  const ratio = canvas.width / rect.width;
  const x = view.mmx((event.clientX - rect.left) * ratio), y = view.mmy((event.clientY - rect.top) * ratio);
  let best = null, bestD = fps.info.pitch_mm / 2;
  for (const site of fps.info.robots) {
    const d = Math.hypot(site.x - x, site.y - y);
    if (d < bestD) { best = site; bestD = d; }
  }
  fps.selected = best ? best.id : null;
  showDetails();
  scheduleDraw();
}

// The status word's set bits by name (the documented ones from info, others as BIT_n).
function decodeStatus(hex) {
  const word = BigInt(`0x${hex}`);
  const names = new Map(fps.info.status_bits.map((b) => [b.bit, b]));
  const set = [];
  for (let n = 0; n < 64; n++) {
    if ((word >> BigInt(n)) & 1n) set.push(names.get(n) || { bit: n, name: `BIT_${n}`, meaning: 'undocumented' });
  }
  return set;
}

function showDetails() {
  const el = $('details');
  if (fps.selected === null || !fps.state) return;
  const robot = fps.state.robots.find((r) => r.id === fps.selected);
  const site = sites.get(fps.selected);
  if (!robot || !site) return;
  const angle = (v) => (v === null ? 'not read' : `${v.toFixed(2)} deg`);
  // Fields one view has and the other not (the simulator's per-robot counters, the host's last
  // reply and read error) are shown when present.
  const rows = [
    ['robot', robot.id], ['bus', `${site.bus} (sextant ${site.sextant})`], ['state', robot.s],
    ['alpha', angle(robot.a)], ['beta', angle(robot.b)], ['firmware', robot.fw || 'unknown'],
    ['status', `0x${robot.st}`], ['requests', robot.req], ['rejected', robot.rej],
    ['collision reports', robot.col], ['receive overflows', robot.ovf],
    ['last reply', robot.ago === undefined ? undefined : (robot.ago === null ? 'none' : `${robot.ago.toFixed(1)} s ago`)],
    ['last read error', robot.err || undefined],
  ].filter(([, v]) => v !== undefined);
  const planned = fps.replay.active && fps.replay.robots.find((r) => r.id === robot.id);
  if (planned) {
    const t = fps.replay.t;
    rows.splice(5, 0, ['plan alpha', `${angleAt(planned.alpha, t).toFixed(2)} deg at ${t.toFixed(2)} s`],
                ['plan beta', `${angleAt(planned.beta, t).toFixed(2)} deg`], ['plan status', planned.status]);
    rows[3][0] = 'live alpha'; rows[4][0] = 'live beta';
  }
  const bits = decodeStatus(robot.st).map((b) => `<li title="${b.meaning}">${b.bit} ${b.name}</li>`).join('');
  el.innerHTML = `<table>${rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join('')}</table>` +
                 `<p>status bits set:</p><ul class="bits" id="status-bits">${bits}</ul>`;
  el.dataset.robot = String(robot.id);
}

// ---- Replaying a plan file ----

// The angle of an arm's [deg, s] points at time t: linear between points, the first angle before
// the first point and the last after the last (as the positioners run a trajectory).
function angleAt(points, t) {
  if (t <= points[0][1]) return points[0][0];
  const last = points.length - 1;
  if (t >= points[last][1]) return points[last][0];
  let lo = 0, hi = last;  // points[lo][1] <= t < points[hi][1]
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (points[mid][1] <= t) lo = mid; else hi = mid;
  }
  const [d0, t0] = points[lo], [d1, t1] = points[hi];
  return d0 + (d1 - d0) * (t - t0) / (t1 - t0);
}

// Whether the arm turns at time t (inside a segment whose ends differ).
function turningAt(points, t) {
  if (t < points[0][1] || t >= points[points.length - 1][1]) return false;
  for (let i = 1; i < points.length; i++) {
    if (t < points[i][1]) return points[i][0] !== points[i - 1][0];
  }
  return false;
}

// Every plan robot of the layout at time t, coloured moving while an arm turns, ready otherwise.
function replayPoses(t) {
  return fps.replay.robots.map((r) => ({
    id: r.id, a: angleAt(r.alpha, t), b: angleAt(r.beta, t),
    s: turningAt(r.alpha, t) || turningAt(r.beta, t) ? 'moving' : 'ready',
  }));
}

// The plan document checked: an error message, or null when it can be replayed.
function planProblem(plan) {
  if (!plan || typeof plan !== 'object' || plan.format !== 'axon-fps-plan') return 'not an axon fps plan (format is not "axon-fps-plan")';
  if (!Array.isArray(plan.robots)) return 'the plan has no list "robots"';
  for (const [n, r] of plan.robots.entries()) {
    if (!r || !Number.isInteger(r.id)) return `robot entry ${n + 1} has no integer id`;
    for (const arm of ['alpha', 'beta']) {
      const pts = r[arm];
      if (!Array.isArray(pts) || pts.length === 0) return `robot ${r.id}: no ${arm} points`;
      for (const [i, p] of pts.entries()) {
        if (!Array.isArray(p) || p.length < 2 || !Number.isFinite(p[0]) || !Number.isFinite(p[1])) {
          return `robot ${r.id}: ${arm} point ${i + 1} is not [deg, s]`;
        }
        if (i > 0 && !(p[1] > pts[i - 1][1])) return `robot ${r.id}: ${arm} point ${i + 1}: time does not increase`;
      }
    }
  }
  return null;
}

// Starts replaying `plan` (the parsed file `name`) from its time 0, paused.
function startReplay(plan, name) {
  const replay = fps.replay;
  const inPlan = new Set();
  replay.robots = [];
  replay.missing = [];
  let duration = Number.isFinite(plan.duration_s) ? plan.duration_s : 0;
  for (const r of plan.robots) {
    inPlan.add(r.id);
    if (!sites.has(r.id)) { replay.missing.push(r.id); continue; }
    replay.robots.push({ id: r.id, status: r.status || '', alpha: r.alpha, beta: r.beta });
    duration = Math.max(duration, r.alpha[r.alpha.length - 1][1], r.beta[r.beta.length - 1][1]);
  }
  replay.absent = fps.info.robots.map((s) => s.id).filter((id) => !inPlan.has(id));
  replay.file = name;
  replay.layout = plan.layout || null;
  replay.duration = duration;
  replay.active = true;
  replay.playing = false;
  $('replay-error').hidden = true;
  $('replay-controls').hidden = false;
  $('replay-banner').hidden = false;
  $('replay-banner').dataset.replaying = 'true';
  $('replay-name').textContent = name;
  $('replay-duration').textContent = duration.toFixed(2);
  const slider = $('replay-slider');
  slider.max = String(duration);
  const counts = {};
  for (const r of replay.robots) counts[r.status] = (counts[r.status] || 0) + 1;
  const statuses = Object.entries(counts).map(([k, v]) => `${v} ${k || 'no status'}`).join(', ');
  const layoutNote = replay.layout && replay.layout !== fps.info.layout ? ` (plan made for layout ${replay.layout})` : '';
  $('replay-info').textContent = `${replay.robots.length} robots replayed${statuses ? `: ${statuses}` : ''}${layoutNote}` +
    (replay.absent.length ? `; ${replay.absent.length} layout robots not in the plan (not drawn): ${listIds(replay.absent)}` : '');
  const missing = $('replay-missing');
  missing.hidden = replay.missing.length === 0;
  missing.textContent = replay.missing.length ? `${replay.missing.length} plan robots not in this layout (not drawn): ${listIds(replay.missing)}` : '';
  showPlay();
  setReplayTime(0);
}

function listIds(ids) {
  return ids.length > 20 ? `${ids.slice(0, 20).join(', ')}, ... (${ids.length - 20} more)` : ids.join(', ');
}

// The slider's time. A range input keeps 15 significant digits of its value (Chromium), so at its
// end it can read a hair (1e-14 s) below the plan's duration: the slider's end is the plan's end.
function sliderTime(slider) {
  const t = Number(slider.value), end = fps.replay.duration;
  return t >= end * (1 - 1e-12) ? end : t;
}

function setReplayTime(t) {
  const replay = fps.replay;
  replay.t = Math.min(Math.max(t, 0), replay.duration);
  $('replay-slider').value = String(replay.t);
  $('replay-time').textContent = replay.t.toFixed(2);
  scheduleDraw();
}

function showPlay() {
  $('replay-play').textContent = fps.replay.playing ? 'pause' : 'play';
  for (const b of $('replay-speeds').querySelectorAll('button')) b.className = Number(b.dataset.speed) === fps.replay.speed ? 'on' : '';
}

let lastFrame = null;  // the previous animation frame's time while playing, ms

function replayFrame(now) {
  const replay = fps.replay;
  if (!replay.playing || !replay.active) return;
  if (lastFrame !== null) setReplayTime(replay.t + replay.speed * (now - lastFrame) / 1000);
  lastFrame = now;
  if (replay.t >= replay.duration) { pauseReplay(); return; }
  requestAnimationFrame(replayFrame);
}

function playReplay() {
  const replay = fps.replay;
  if (!replay.active || replay.playing) return;
  if (replay.t >= replay.duration) setReplayTime(0);  // play at the end starts again
  replay.playing = true;
  lastFrame = null;
  showPlay();
  requestAnimationFrame(replayFrame);
}

function pauseReplay() {
  fps.replay.playing = false;
  showPlay();
}

function backToLive() {
  const replay = fps.replay;
  replay.playing = false;
  replay.active = false;
  $('replay-controls').hidden = true;
  $('replay-banner').hidden = true;
  $('replay-banner').dataset.replaying = 'false';
  $('plan-file').value = '';
  scheduleDraw();
}

function showReplayError(message) {
  const el = $('replay-error');
  el.textContent = message;
  el.hidden = false;
}

async function loadPlanFile(file) {
  let plan;
  try {
    plan = JSON.parse(await file.text());
  } catch (error) {
    showReplayError(`${file.name}: not JSON (${error.message})`);
    return;
  }
  const problem = planProblem(plan);
  if (problem) { showReplayError(`${file.name}: ${problem}`); return; }
  startReplay(plan, file.name);
}

function setUpReplay() {
  $('plan-file').addEventListener('change', (event) => {
    const file = event.target.files[0];
    if (file) loadPlanFile(file);
  });
  $('replay-play').addEventListener('click', () => (fps.replay.playing ? pauseReplay() : playReplay()));
  $('replay-live').addEventListener('click', backToLive);
  $('replay-slider').addEventListener('input', (event) => setReplayTime(sliderTime(event.target)));
  for (const b of $('replay-speeds').querySelectorAll('button')) {
    b.addEventListener('click', () => { fps.replay.speed = Number(b.dataset.speed); showPlay(); });
  }
}

// For scripts: the replay's controls as functions (the page's buttons and slider call the same).
Object.assign(fps.replay, { seek: setReplayTime, play: playReplay, pause: pauseReplay, live: backToLive });

start().catch((error) => { $('conn').textContent = `error: ${error}`; });
