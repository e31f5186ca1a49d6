'use strict';
// The c4g page: a server answering one robot controller. Per open axis its mode, the manual's label
// and where the mode stands (start / cruise / running / end); per arm the drives; the phase of the
// application; two histograms (Chart.js from Debian's libjs-chart.js, served at /javascript/chart.js/)
// of the cycle timing: receive-to-send with the answer deadline marked, and the controller's period
// with its nominal value marked; late and unanswered replies, the Safety layer's following-error and
// drive-off replies, the following error of each axis as the cycle last measured it (|D1 - D3|, with
// its peak since the axis entered its mode), the controller's errors and the latest events. The server pushes the state
// (/ws?source=c4g, docs/dashboard.md). window.axonC4g holds what the page shows, for scripts and tests.

const c4g = {
  info: null,     // the modes' table, the controller errors' meanings (/api/c4g/info)
  state: null,    // the latest state message
  seq: 0,
  messages: 0,
  charts: null,   // Chart.js charts `cycle` and `period`; null without Chart.js
  marks: {},      // per chart the marker drawn last: {value_us, x} (x: its pixel)
  shown: { seq: 0, modes: [] },  // what the page was last drawn from
};
window.axonC4g = c4g;

const $ = (id) => document.getElementById(id);
const num = (v, digits) => (typeof v === 'number' ? v.toFixed(digits) : '-');

// Draws a vertical dashed line at options.plugins.axonMarker.value_us on a histogram whose bins
// have width_us (the first bin starts at 0), and notes where in c4g.marks.
const markerPlugin = {
  id: 'axonMarker',
  afterDatasetsDraw(chart, args, opts) {
    if (!opts || !(opts.width_us > 0) || !(opts.value_us > 0)) return;
    const x = chart.scales.x.getPixelForValue(opts.value_us / opts.width_us - 0.5);
    const { top, bottom } = chart.chartArea;
    const ctx = chart.ctx;
    ctx.save();
    ctx.strokeStyle = opts.colour;
    ctx.setLineDash([6, 4]);
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(x, top);
    ctx.lineTo(x, bottom);
    ctx.stroke();
    ctx.fillStyle = opts.colour;
    ctx.fillText(opts.label, Math.min(x + 4, chart.chartArea.right - 80), top + 12);
    ctx.restore();
    c4g.marks[opts.key] = { value_us: opts.value_us, x };
  },
};

async function start() {
  c4g.info = await (await fetch('/api/c4g/info')).json();
  $('title').textContent = c4g.info.command;
  buildCharts();
  axonConnect('c4g', (message) => {
    c4g.state = message.state;
    c4g.seq = message.seq;
    c4g.messages++;
    show();
  });
}

function histogram(canvas, key, title, colour) {
  return new Chart(canvas, {
    type: 'bar',
    data: { labels: [], datasets: [{ label: 'cycles', data: [], backgroundColor: [], barPercentage: 1, categoryPercentage: 1 }] },
    options: {
      animation: false, maintainAspectRatio: false,
      scales: { x: { title: { display: true, text: `${title} [µs] (bin upper edge)` }, ticks: { maxTicksLimit: 12 } },
                y: { type: 'logarithmic', title: { display: true, text: 'cycles' } } },
      plugins: { legend: { display: false }, title: { display: true, text: title },
                 axonMarker: { key, colour, label: '', value_us: 0, width_us: 0 } },
    },
    plugins: [markerPlugin],
  });
}

function buildCharts() {
  if (typeof Chart === 'undefined') {
    $('chart-missing').hidden = false;
    for (const id of ['hist-cycle', 'hist-period']) $(id).parentElement.hidden = true;
    return;
  }
  c4g.charts = {
    cycle: histogram($('hist-cycle'), 'cycle', 'receive to send', '#c62828'),
    period: histogram($('hist-period'), 'period', 'inter-packet period', '#1565c0'),
  };
}

function show() {
  const s = c4g.state;
  if (!s) return;
  showApp(s.app);
  showAxes(s.axes, s.arms);
  showSafety(s.safety, s.counters, s.axes);
  showTiming(s.timing);
  showServer(s.server, s.controller_errors, s.events);
  c4g.shown = { seq: c4g.seq, modes: s.axes.map((a) => a.mode) };
}

function showApp(app) {
  $('app-name').textContent = app.name;
  const phase = $('phase');
  phase.dataset.phase = app.phase || '';
  phase.textContent = app.phase || 'no phase machine';
  $('app-status').textContent = app.status;
  $('app-error').hidden = !app.error;
  $('app-error').textContent = app.error ? `error: ${app.error}` : '';
}

function modeTitle(code) {
  const m = c4g.info.modes.find((x) => x.code === code);
  return m ? m.description : 'not a mode the interface defines';
}

function showAxes(axes, arms) {
  const body = $('axes').tBodies[0];
  body.innerHTML = '';
  for (const a of axes) {
    const tr = body.insertRow();
    tr.dataset.mode = a.mode;
    tr.dataset.phase = a.phase;
    tr.className = a.mode === 0 ? '' : 'open';
    const cells = [a.i, a.arm ? `${a.arm}.${a.axis}` : '-', a.mode, a.label, a.name, a.phase || '-', num(a.in_mode_s, 1),
                   num(a.following_error, 5), num(a.following_error_peak, 5), num(a.fe_threshold, 3)];
    for (const v of cells) tr.insertCell().textContent = v;
    tr.cells[3].title = modeTitle(a.mode);
    // Against the threshold in the modes the Safety checks; near it (over 80 %) shown as a warning.
    const fe = tr.cells[7];
    fe.dataset.fe = a.following_error;
    fe.className = a.fe_checked && a.fe_threshold > 0 && a.following_error > 0.8 * a.fe_threshold ? 'near' : '';
    fe.title = a.fe_checked ? 'checked against the threshold in this mode' : 'not checked in this mode';
  }
  const list = $('arms');
  list.innerHTML = '';
  for (const arm of arms) {
    const li = document.createElement('li');
    li.dataset.arm = arm.arm;
    li.dataset.drives = arm.drives || 'unknown';
    li.className = arm.drives === 'on' ? 'on' : '';
    li.textContent = `arm ${arm.arm}: drives ${arm.drives || 'unknown'}${arm.exit_sent ? ', exit from open sent' : ''}` +
                     ` (drives off ${arm.drives_off}×)`;
    list.appendChild(li);
  }
}

function showSafety(safety, c, axes) {
  const box = $('safety');
  box.dataset.fault = safety.fault;
  box.className = safety.fault === 'none' ? 'ok' : 'bad';
  box.textContent = safety.fault === 'none' ? 'Safety: no fault'
    : `Safety: ${safety.fault}${safety.fault_axis >= 0 ? ` (axis ${safety.fault_axis + 1})` : ''}` +
      `${safety.obeyed ? ', drives off obeyed' : ', asking for drive off'}`;
  axonRows($('counters'), [
    ['cycles', c.cyclic],
    ['late replies', c.late_replies],
    ['missed (unanswered, send errors)', c.unanswered + c.send_errors],
    ['safe replies', c.safe_replies],
    ['application late', c.app_late],
    ['protocol errors', c.protocol_errors],
    ['refused mode changes', c.refused_mode_changes],
    ['foreign datagrams', c.foreign],
    ['drive-off replies', safety.drive_off_replies],
  ]);
  const thresholds = axes.map((a) => num(a.fe_threshold, 2));
  const largest = axes.reduce((best, a) => (a.following_error > (best ? best.following_error : -1) ? a : best), null);
  axonRows($('following'), [
    ['largest now [motor turns]', largest ? `${num(largest.following_error, 5)} (axis ${largest.i})` : '-'],
    ['following-error replies (508)', safety.following_error_replies],
    ['following-error fault', safety.fault === 'following error' ? `axis ${safety.fault_axis + 1}` : 'none'],
    ['thresholds [motor turns]', thresholds.length ? thresholds.join(' ') : '-'],
    ['currents clamped', safety.currents_clamped],
  ]);
}

function showTiming(t) {
  axonRows($('timing'), [
    ['deadline', `${num(t.deadline_us, 0)} µs`],
    ['receive to send p50 / p99 / p99.9', `${num(t.p50_us, 0)} / ${num(t.p99_us, 0)} / ${num(t.p999_us, 0)} µs`],
    ['worst', `${num(t.worst_cycle_us, 1)} µs`],
    ['period', `${t.nominal_known ? num(t.nominal_period_us / 1000, 1) + ' ms' : 'unknown'} (min ${num(t.period_min_us, 0)}, max ${num(t.period_max_us, 0)} µs)`],
    ['late (over the deadline)', t.late],
  ]);
  if (!c4g.charts) return;
  fill(c4g.charts.cycle, t.cycle_hist, t.deadline_us, `deadline ${num(t.deadline_us, 0)} µs`);
  fill(c4g.charts.period, t.period_hist, t.nominal_period_us, `nominal ${num(t.nominal_period_us, 0)} µs`);
}

// One histogram: its bins (the last one open above), bars past the marker in the marker's colour.
function fill(chart, hist, marker_us, label) {
  const n = hist.counts.length;
  const w = hist.width_us;
  chart.data.labels = hist.counts.map((_, k) => (k === n - 1 ? `>${num((n - 1) * w, 0)}` : num((k + 1) * w, 0)));
  chart.data.datasets[0].data = hist.counts.map((c) => (c > 0 ? c : null));
  const m = chart.options.plugins.axonMarker;
  chart.data.datasets[0].backgroundColor = hist.counts.map((_, k) => ((k + 1) * w > marker_us && m.key === 'cycle' ? '#e57373' : '#546e7a'));
  Object.assign(m, { value_us: marker_us, width_us: w, label });
  chart.update('none');
}

function showServer(server, errors, events) {
  axonRows($('server'), [
    ['state', server.state],
    ['controller', server.controller || 'none yet'],
    ['listening', server.local],
    ['freezing', server.freeze],
    ['sessions', server.sessions],
  ]);
  const counts = Object.entries(errors.counts).map(([name, n]) => `${name} ${n}×`);
  const box = $('controller-errors');
  box.textContent = counts.length ? counts.join(', ') : 'none';
  const meaning = errors.last && c4g.info.controller_errors.find((e) => e.name === errors.last);
  box.title = meaning ? meaning.meaning : '';
  const list = $('events');
  list.innerHTML = '';
  for (const e of events.slice(-15).reverse()) {
    const li = document.createElement('li');
    li.textContent = `cycle ${e.cycle}: ${e.text}`;
    list.appendChild(li);
  }
}

start();
