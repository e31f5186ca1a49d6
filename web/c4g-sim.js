'use strict';
// The c4g simulator page (`axon sim c4g --http`): what the simulated controller itself does, beside
// the c4g page of the PC server it talks to. Per arm the joints at the link and their targets, the
// drives and the open mode the robot program asked for; per open axis the mode it is in and the one
// the PC's last reply asked for; the program with its step under way; the packets sent and how the
// PC's replies were judged; the communication error; the controller's events. A trace of the joints
// (Chart.js, Debian's libjs-chart.js at /javascript/chart.js/) is kept here from the pushed states
// (/ws?source=c4g-sim, docs/dashboard.md). window.axonC4gSim holds what the page shows, for tests.

const TRACE_SECONDS = 20;
const JOINT_COLOURS = ['#1565c0', '#ef6c00', '#2e7d32', '#6a1b9a', '#c62828', '#00838f', '#5d4037', '#455a64', '#ad1457', '#9e9d24'];

const c4gSim = {
  info: null,    // robot, program steps, modes (/api/c4g-sim/info)
  state: null,   // the latest state message
  seq: 0,
  messages: 0,
  chart: null,   // the joint trace; null without Chart.js
  trace: [],     // [{t, joints: [deg, ...]}] of arm 1, the last TRACE_SECONDS of simulated time
};
window.axonC4gSim = c4gSim;

const $ = (id) => document.getElementById(id);
const num = (v, digits) => (typeof v === 'number' ? v.toFixed(digits) : '-');

async function start() {
  c4gSim.info = await (await fetch('/api/c4g-sim/info')).json();
  $('title').textContent = `${c4gSim.info.robot} to ${c4gSim.info.server} (${c4gSim.info.command})`;
  $('program-name').textContent = `program: ${c4gSim.info.program}`;
  const list = $('program');
  for (const step of c4gSim.info.steps) {
    const li = document.createElement('li');
    li.textContent = step;
    list.appendChild(li);
  }
  buildChart();
  axonConnect('c4g-sim', (message) => {
    c4gSim.state = message.state;
    c4gSim.seq = message.seq;
    c4gSim.messages++;
    show();
  });
}

function buildChart() {
  if (typeof Chart === 'undefined') {
    $('chart-missing').hidden = false;
    $('trace').parentElement.hidden = true;
    return;
  }
  c4gSim.chart = new Chart($('trace'), {
    type: 'line',
    data: { datasets: [] },
    options: {
      animation: false, maintainAspectRatio: false, parsing: false, normalized: true,
      elements: { point: { radius: 0 }, line: { borderWidth: 1.5 } },
      scales: { x: { type: 'linear', title: { display: true, text: 'simulated time [s]' } },
                y: { title: { display: true, text: 'joint position at the link [deg]' } } },
      plugins: { title: { display: true, text: 'arm 1 joints' } },
    },
  });
}

function modeTitle(code) {
  const m = c4gSim.info.modes.find((x) => x.code === code);
  return m ? m.description : 'not a mode the interface defines';
}

function show() {
  const s = c4gSim.state;
  if (!s) return;
  showProgram(s);
  showJoints(s.arms);
  showAxes(s.axes);
  showCounters(s);
  showEvents(s.events);
  addTrace(s);
}

function showProgram(s) {
  const phase = $('phase');
  phase.dataset.phase = s.ended ? 'done' : s.phase;
  phase.textContent = s.ended ? `ended (${s.phase})` : s.phase;
  const step = $('step');
  const sc = s.scenario;
  step.dataset.step = sc.step;
  step.dataset.kind = sc.kind || '';
  step.textContent = sc.kind ? `step ${sc.step} of ${sc.steps}: ${sc.kind}` : (sc.done ? 'program completed' : 'program ended');
  $('app-error').hidden = !sc.failed;
  $('app-error').textContent = sc.failed ? 'the program failed (see the events)' : '';
  Array.from($('program').children).forEach((li, k) => {
    li.className = k + 1 === sc.step && sc.kind ? 'now' : (k + 1 < sc.step ? 'done' : '');
  });
}

function showJoints(arms) {
  const body = $('joints').tBodies[0];
  body.innerHTML = '';
  const list = $('arms');
  list.innerHTML = '';
  for (const arm of arms) {
    arm.joints_deg.forEach((deg, k) => {
      const tr = body.insertRow();
      tr.dataset.arm = arm.arm;
      tr.dataset.joint = k + 1;
      tr.dataset.deg = deg;
      for (const v of [`${arm.arm}.${k + 1}`, num(deg, 3), num(arm.targets_deg[k], 3)]) tr.insertCell().textContent = v;
    });
    const li = document.createElement('li');
    li.dataset.arm = arm.arm;
    li.dataset.drives = arm.drives;
    li.dataset.programMode = arm.program_mode;
    li.className = arm.drives === 'on' ? 'on' : '';
    li.textContent = `arm ${arm.arm}: drives ${arm.drives}; program asked for ` +
                     (arm.program_mode ? `mode ${arm.program_label} (GO OPEN)` : 'no open mode');
    list.appendChild(li);
  }
}

function showAxes(axes) {
  const body = $('axes').tBodies[0];
  body.innerHTML = '';
  for (const a of axes) {
    const tr = body.insertRow();
    tr.dataset.mode = a.mode;
    tr.dataset.pcRequest = a.pc_request;
    tr.className = a.mode === 0 ? '' : 'open';
    const cells = [a.i, `${a.arm}.${a.axis}`, a.mode, a.label, a.pc_label, num(a.position, 4), num(a.target, 4),
                   num(a.error, 5), num(a.current, 3)];
    for (const v of cells) tr.insertCell().textContent = v;
    tr.cells[3].title = modeTitle(a.mode);
    tr.cells[4].title = modeTitle(a.pc_request);
  }
}

function showCounters(s) {
  const c = s.counters;
  const box = $('comm');
  box.dataset.error = s.communication_error;
  box.className = s.communication_error ? 'bad' : 'ok';
  box.textContent = s.communication_error ? 'Communication error: ERR_C4GOPEN_UDP (10 misses in a row), drives off'
    : `Communication: no error (${c.consecutive_misses} misses in a row now)`;
  axonRows($('counters'), [
    ['cycles', c.ticks],
    ['packets sent (sync, init, cyclic)', `${c.packets_sent} (${c.sync_sent}, ${c.init_sent}, ${c.cyclic_sent})`],
    ['replies in time', c.replies_ok],
    ['missed replies', c.misses],
    ['late replies', c.late_replies],
    ['most misses in a row', c.max_consecutive_misses],
    ['wrong number / size / malformed', `${c.wrong_number} / ${c.wrong_size} / ${c.malformed}`],
    ['refused mode requests', c.refused_requests],
    ['frozen cycles', c.frozen_cycles],
    ['saturated axis-cycles', c.saturated_cycles],
    ['schedule overruns', c.overruns],
  ]);
  axonRows($('rtt'), [
    ['replies timed', s.rtt.count],
    ['mean', `${num(s.rtt.mean_us, 0)} µs`],
    ['max', `${num(s.rtt.max_us, 0)} µs`],
    ['simulated time', `${num(s.time_s, 1)} s`],
  ]);
}

function showEvents(events) {
  const list = $('events');
  list.innerHTML = '';
  for (const e of events.slice(-20).reverse()) {
    const li = document.createElement('li');
    li.className = e.level;
    li.textContent = `${num(e.t, 3)} s ${e.name}: ${e.text}`;
    list.appendChild(li);
  }
}

// Arm 1's joints into the trace (a restart of the simulated time starts it again).
function addTrace(s) {
  const arm = s.arms.find((a) => a.arm === 1) || s.arms[0];
  if (!arm) return;
  const last = c4gSim.trace[c4gSim.trace.length - 1];
  if (last && s.time_s < last.t) c4gSim.trace = [];
  if (!last || s.time_s > last.t) c4gSim.trace.push({ t: s.time_s, joints: arm.joints_deg });
  while (c4gSim.trace.length && c4gSim.trace[0].t < s.time_s - TRACE_SECONDS) c4gSim.trace.shift();
  if (!c4gSim.chart) return;
  const chart = c4gSim.chart;
  chart.data.datasets = arm.joints_deg.map((_, k) => ({
    label: `joint ${k + 1}`, borderColor: JOINT_COLOURS[k % JOINT_COLOURS.length],
    data: c4gSim.trace.map((p) => ({ x: p.t, y: p.joints[k] })),
  }));
  chart.update('none');
}

start();
