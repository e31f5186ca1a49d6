'use strict';
// The blmc page: per board, scopes of both motors' current, position and velocity (Chart.js from
// Debian's libjs-chart.js, served at /javascript/chart.js/), the status flags, the error code with
// its meaning, the control loop's cycles, overruns and jitter histogram, and the safety limits in
// force. The server decimates the traces (50 samples a second, the last 12 s) and pushes the state
// (/ws?source=blmc, docs/dashboard.md). window.axonBlmc holds what the page shows, for scripts and tests.

const MOTOR_COLOURS = ['#1565c0', '#ef6c00'];
const SCOPES = [
  { key: 'current', title: 'current [A]', series: ['i1', 'i2'] },
  { key: 'position', title: 'position [motor rev]', series: ['p1', 'p2'] },
  { key: 'velocity', title: 'velocity [krpm]', series: ['v1', 'v2'] },
];

const blmc = {
  info: null,      // boards, limits, flag and error code meanings (/api/blmc/info)
  state: null,     // the latest state message
  seq: 0,
  messages: 0,
  board: 0,        // the board shown
  charts: null,    // Chart.js charts by scope key, and `jitter`; null without Chart.js
  shown: { seq: 0, t: null },  // what the scopes were last drawn from
};
window.axonBlmc = blmc;

const $ = (id) => document.getElementById(id);
const text = (v, digits) => (typeof v === 'number' ? v.toFixed(digits) : '-');

async function start() {
  blmc.info = await (await fetch('/api/blmc/info')).json();
  const names = blmc.info.boards.map((b) => b.name);
  $('title').textContent = `${names.join(', ')} (${blmc.info.command})`;
  if (names.length > 1) {
    const select = $('board');
    names.forEach((n, i) => select.add(new Option(n, i)));
    select.hidden = false;
    select.onchange = () => { blmc.board = Number(select.value); showLimits(); show(); };
  }
  buildFlags();
  showLimits();
  buildCharts();
  connect();
}

function buildFlags() {
  for (const f of blmc.info.flags) {
    const li = document.createElement('li');
    li.dataset.flag = f.name;
    li.title = f.meaning;
    li.textContent = f.name.replace('_', ' ');
    $('flags').appendChild(li);
  }
}

function showLimits() {
  const l = blmc.info.boards[blmc.board].limits;
  if (!l) {
    axonRows($('limits'), [['none', 'monitoring only: no control loop']]);
    return;
  }
  const pairs = [
    ['motors', ['1', '2'].filter((m, i) => l.motors[i]).join(', ') || 'none'],
    ['current clamp', `${l.max_current_a} A`],
    ['velocity limit', `${l.max_velocity_krpm} krpm`],
    ['stale after', `${l.stale_after_ms} ms (status ${l.status_stale_after_ms} ms)`],
  ];
  l.position.forEach((p, i) => pairs.push([`motor ${i + 1} position`, p.enabled ? `${p.min_rev} .. ${p.max_rev} rev` : 'no limit']));
  axonRows($('limits'), pairs);
}

function buildCharts() {
  if (typeof Chart === 'undefined') {
    $('chart-missing').hidden = false;
    for (const s of SCOPES) $(`scope-${s.key}`).parentElement.hidden = true;
    $('jitter').parentElement.hidden = true;
    return;
  }
  blmc.charts = {};
  for (const s of SCOPES) {
    blmc.charts[s.key] = new Chart($(`scope-${s.key}`), {
      type: 'line',
      data: { datasets: s.series.map((key, i) => ({ label: `motor ${i + 1}`, data: [], borderColor: MOTOR_COLOURS[i],
                                                    borderWidth: 1.5, pointRadius: 0 })) },
      options: {
        animation: false, parsing: false, normalized: true, maintainAspectRatio: false,
        scales: { x: { type: 'linear', title: { display: true, text: 't [s]' } } },
        plugins: { title: { display: true, text: s.title }, legend: { position: 'right' } },
      },
    });
  }
  const bounds = blmc.info.jitter_bounds_us;
  blmc.charts.jitter = new Chart($('jitter'), {
    type: 'bar',
    data: { labels: bounds.map((b) => `≤${b}`).concat([`>${bounds[bounds.length - 1]}`]),
            datasets: [{ label: 'cycles', data: [], backgroundColor: '#546e7a' }] },
    options: { animation: false, maintainAspectRatio: false,
               scales: { x: { title: { display: true, text: '|period - nominal| [µs]' } },
                         y: { type: 'logarithmic', title: { display: true, text: 'cycles' } } },
               plugins: { legend: { display: false } } },
  });
}

function connect() {
  axonConnect('blmc', (message) => {
    blmc.state = message.state;
    blmc.seq = message.seq;
    blmc.messages++;
    show();
  });
}

function show() {
  if (!blmc.state) return;
  const b = blmc.state.boards[blmc.board];
  showStatus(b);
  showLoop(blmc.state.loop);
  showScopes(b.samples);
}

function showStatus(b) {
  const e = $('error');
  e.dataset.code = b.have_status ? b.error.code : '';
  e.className = b.error.code !== 0 ? 'bad' : 'ok';
  e.innerHTML = '';
  e.append(b.have_status ? `error ${b.error.code} ${b.error.name}` : 'no status yet');
  const meaning = document.createElement('span');
  meaning.className = 'meaning';
  meaning.textContent = b.have_status ? b.error.meaning : '';
  e.append(meaning);
  for (const li of $('flags').children) li.className = b.flags[li.dataset.flag] ? 'on' : '';
  const f = $('fault');
  f.hidden = !b.tripped;
  f.dataset.kind = b.fault ? b.fault.kind : '';
  f.textContent = b.fault ? `safety stop: ${b.fault.text}` : 'safety stop (the run is ending)';
  const counts = Object.entries(b.errors).map(([name, n]) => `${name} ${n}×`);
  $('errors').textContent = counts.length ? `errors reported: ${counts.join(', ')}` : '';
}

function showLoop(loop) {
  if (!loop) {
    axonRows($('loop'), [['loop', 'none (monitoring)']]);
    return;
  }
  axonRows($('loop'), [
    ['state', loop.running ? 'running' : 'ended'],
    ['cycles', loop.cycles],
    ['overruns', loop.overruns],
    ['missed deadlines', loop.missed],
    ['records lost', loop.records_lost],
    ['last period', `${text(loop.period_us, 1)} µs`],
    ['jitter mean / max', `${text(loop.jitter_mean_us, 1)} / ${text(loop.jitter_max_us, 1)} µs`],
  ]);
  if (blmc.charts) {
    blmc.charts.jitter.data.datasets[0].data = loop.jitter;
    blmc.charts.jitter.update('none');
  }
}

function showScopes(samples) {
  const n = samples.n;
  const latest = [];
  for (const s of SCOPES) {
    const values = s.series.map((key) => samples[key]);
    latest.push([s.title, values.map((v) => text(v[n - 1], 4))]);
    if (!blmc.charts) continue;
    const chart = blmc.charts[s.key];
    values.forEach((v, i) => { chart.data.datasets[i].data = samples.t.map((t, k) => ({ x: t, y: v[k] })); });
    chart.update('none');
  }
  const body = $('latest').tBodies[0];
  body.innerHTML = '';
  for (const [title, [m1, m2]] of latest) {
    const tr = body.insertRow();
    tr.insertCell().textContent = title;
    tr.insertCell().textContent = m1;
    tr.insertCell().textContent = m2;
  }
  blmc.shown = { seq: blmc.seq, t: n ? samples.t[n - 1] : null };
}

start();
