'use strict';
// The fps page: the focal plane drawn from the layout (/api/fps/info) with every robot's arms at
// their live angles and its state, pushed by the server (/ws?source=fps, docs/dashboard.md).
// window.axonFps holds what the page shows (info, state, what was drawn) for scripts and tests.

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
  drawn: { seq: 0, robots: 0 },  // what the canvas shows
  selected: null,   // id of the robot whose details are shown
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
  $('title').textContent = `${fps.info.layout}, ${fps.info.robots.length} robots`;
  buildLegend();
  $('plane').addEventListener('click', onClick);
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
  if (!fps.info || !fps.state) return;
  view = fitView(canvas);
  const ctx = canvas.getContext('2d');
  ctx.clearRect(0, 0, w, h);
  drawFiducials(ctx);
  const lock = fps.state.lock;
  let drawn = 0;
  for (const robot of fps.state.robots) {
    const site = sites.get(robot.id);
    if (!site) continue;
    drawRobot(ctx, site, robot, lock);
    drawn++;
  }
  fps.drawn = { seq: fps.seq, robots: drawn };
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
  const cause = lock.locked && lock.robot === robot.id;
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
  const rows = [
    ['robot', robot.id], ['bus', `${site.bus} (sextant ${site.sextant})`], ['state', robot.s],
    ['alpha', `${robot.a.toFixed(2)} deg`], ['beta', `${robot.b.toFixed(2)} deg`], ['firmware', robot.fw],
    ['status', `0x${robot.st}`], ['requests', robot.req], ['rejected', robot.rej],
    ['collision reports', robot.col], ['receive overflows', robot.ovf],
  ];
  const bits = decodeStatus(robot.st).map((b) => `<li title="${b.meaning}">${b.bit} ${b.name}</li>`).join('');
  el.innerHTML = `<table>${rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join('')}</table>` +
                 `<p>status bits set:</p><ul class="bits" id="status-bits">${bits}</ul>`;
  el.dataset.robot = String(robot.id);
}

start().catch((error) => { $('conn').textContent = `error: ${error}`; });
