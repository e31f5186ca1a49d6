'use strict';
// What every family page shares: the WebSocket of live state (/ws?source=NAME, docs/dashboard.md),
// reconnected after a second when it closes, with its state shown in the header's #conn.

// Calls onMessage({source, seq, state}) for each state of `source` the server pushes.
function axonConnect(source, onMessage) {
  const conn = document.getElementById('conn');
  const scheme = location.protocol === 'https:' ? 'wss' : 'ws';
  const ws = new WebSocket(`${scheme}://${location.host}/ws?source=${source}`);
  ws.onopen = () => { conn.textContent = 'live'; conn.className = 'live'; };
  ws.onclose = () => {
    conn.textContent = 'disconnected, reconnecting';
    conn.className = '';
    setTimeout(() => axonConnect(source, onMessage), 1000);
  };
  ws.onmessage = (event) => {
    const message = JSON.parse(event.data);
    if (message.source === source) onMessage(message);
  };
}

// Fills `table` with one row per [name, value] pair (text only), replacing what it held.
function axonRows(table, pairs) {
  table.innerHTML = '';
  for (const [name, value] of pairs) {
    const tr = table.insertRow();
    tr.insertCell().textContent = name;
    tr.insertCell().textContent = value;
  }
}
