// The viewer page: long-polls the server for frames of each render slot
// (half floats), shows them through WebGL2 (gl.js), and sends the edited
// scene back as JSON; the server validates it with the scene parser and
// answers an error message that the page shows.
import { Display, halfToFloat } from './gl.js';
import { buildSceneControls } from './controls.js';
import { orbit, pan, zoom } from './camera.js';

const $ = (id) => document.getElementById(id);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// What the page knows; exposed as window.nieblaView for the browser test and the benchmark.
const state = {
  label: '', scene: null, compare: null, integrators: [], reloads: 0,
  frames: [null, null], lastId: [0, 0], frameCount: [0, 0],
  sentAt: {}, postAt: {}, latencies: [], relativeMse: null, error: null, saved: null, lastVersion: 1, busy: false,
};
window.nieblaView = state;
// The benchmark edits through the same path as the controls: nieblaView.edit(interactive).
state.edit = (interactive) => sendEdit(interactive);

const HALF = new Float32Array(65536).map((_, h) => halfToFloat(h));
let display;

function showError(message) {
  state.error = message;
  $('error').hidden = !message;
  $('error').textContent = message ?? '';
}

// ---- edits ---------------------------------------------------------------
let pending = null, inFlight = false;

// Send the edited scene (the latest wins while a request is in flight).
function sendEdit(interactive) {
  pending = { interactive };
  state.busy = true;
  if (!inFlight) flush();
}

async function flush() {
  inFlight = true;
  while (pending) {
    const { interactive } = pending;
    pending = null;
    const body = {
      scene: state.scene, compare: state.compare, interactive,
      preview_scale: Number($('preview-scale').value) || 2, max_spp: Number($('max-spp').value) || 65536,
    };
    const sent = performance.now();
    try {
      const response = await fetch('api/scene', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
      const reply = await response.json();
      if (response.ok) {
        state.sentAt[reply.version] = sent;
        state.postAt[reply.version] = performance.now();
        state.lastVersion = reply.version;
        showError(null);
      } else {
        showError(reply.error);
      }
    } catch (e) {
      showError(`connection lost: ${e}`);
    }
  }
  inFlight = false;
  state.busy = false;
}

// ---- state and controls --------------------------------------------------
function integratorOptions(select, chosen) {
  select.replaceChildren(...state.integrators.map((e) => {
    const option = new Option(e.name, e.name, false, e.name === chosen);
    option.title = e.summary;
    return option;
  }));
}

function fillIntegrator() {
  state.scene.render ??= {};
  const integrator = state.scene.render.integrator ?? { type: 'single' };
  integratorOptions($('integrator'), integrator.type);
  $('integrator-json').value = JSON.stringify(integrator);
}

async function loadState() {
  const reply = await (await fetch('api/state')).json();
  Object.assign(state, { label: reply.label, scene: reply.scene, compare: reply.compare, integrators: reply.integrators });
  $('label').textContent = reply.label;
  $('max-spp').value = reply.max_spp;
  $('preview-scale').value = reply.preview_scale;
  const camera = state.scene.camera;
  $('canvas').width = camera.width;
  $('canvas').height = camera.height;
  fillIntegrator();
  integratorOptions($('compare-integrator'), state.compare?.type ?? 'volpath');
  buildSceneControls($('scene-controls'), state.scene, sendEdit);
}

function wireControls() {
  const redraw = () => display.draw();
  $('exposure').addEventListener('input', () => {
    display.settings.exposure = Number($('exposure').value);
    $('exposure-value').textContent = $('exposure').value;
    redraw();
  });
  $('curve').addEventListener('change', () => { display.settings.curve = Number($('curve').value); redraw(); });
  $('wipe').addEventListener('input', () => { display.settings.wipe = Number($('wipe').value); redraw(); });
  $('error-scale').addEventListener('input', () => { display.settings.errorScale = Number($('error-scale').value); redraw(); });
  $('integrator').addEventListener('change', () => {
    state.scene.render.integrator = { type: $('integrator').value };
    $('integrator-json').value = JSON.stringify(state.scene.render.integrator);
    sendEdit(false);
  });
  const applyJson = () => {
    try {
      state.scene.render.integrator = JSON.parse($('integrator-json').value);
    } catch (e) {
      showError(`render.integrator: not JSON: ${e.message}`);
      return;
    }
    sendEdit(false);
  };
  $('integrator-json').addEventListener('change', applyJson);
  $('integrator-json').addEventListener('keydown', (e) => { if (e.key === 'Enter' && e.ctrlKey) applyJson(); });
  for (const id of ['max-spp', 'preview-scale']) $(id).addEventListener('change', () => sendEdit(false));
  const split = () => {
    const mode = Number($('split-mode').value);
    display.settings.mode = mode;
    state.compare = mode === 0 ? null : { type: $('compare-integrator').value };
    state.frames[1] = null;
    sendEdit(false);
    redraw();
  };
  $('split-mode').addEventListener('change', split);
  $('compare-integrator').addEventListener('change', split);
  for (const format of ['exr', 'png', 'scene']) {
    $(`save-${format}`).addEventListener('click', async () => {
      const response = await fetch('api/save', { method: 'POST', headers: { 'Content-Type': 'application/json' },
        body: JSON.stringify({ format, slot: 0, exposure: display.settings.exposure }) });
      const reply = await response.json();
      if (response.ok) { state.saved = reply.file; $('saved').textContent = `saved ${reply.file}`; } else showError(reply.error);
    });
  }
  wireMouse($('canvas'));
}

function wireMouse(canvas) {
  let drag = null, wheelTimer = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY, pan: e.button !== 0 || e.shiftKey }; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener('pointermove', (e) => {
    // The inspector follows the cursor when not dragging (its text change
    // repaints the page: during a drag that is browser time taken from frames).
    if (!drag) { inspect(e); return; }
    const scaleToImage = canvas.height / canvas.getBoundingClientRect().height;
    const dx = (e.clientX - drag.x) * scaleToImage, dy = (e.clientY - drag.y) * scaleToImage;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.pan) pan(state.scene.camera, dx, dy, canvas.height); else orbit(state.scene.camera, dx, dy);
    sendEdit(true);
  });
  const end = () => { if (drag) { drag = null; sendEdit(false); } };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    zoom(state.scene.camera, Math.sign(e.deltaY) * 0.1);
    sendEdit(true);
    clearTimeout(wheelTimer);
    wheelTimer = setTimeout(() => sendEdit(false), 250);
  }, { passive: false });
}

// The radiance under the cursor (slot A, and slot B in a split view).
function inspect(e) {
  const rect = $('canvas').getBoundingClientRect();
  const u = (e.clientX - rect.left) / rect.width, v = (e.clientY - rect.top) / rect.height;
  const parts = state.frames.map((f, slot) => {
    if (!f || u < 0 || v < 0 || u >= 1 || v >= 1) return null;
    const x = Math.floor(u * f.width), y = Math.floor(v * f.height), i = 3 * (y * f.width + x);
    const rgb = [0, 1, 2].map((c) => HALF[f.halves[i + c]].toPrecision(4)).join(', ');
    return `${'AB'[slot]}(${x}, ${y}) = (${rgb})`;
  }).filter(Boolean);
  $('inspector').textContent = parts.join('   ');
}

// ---- frames --------------------------------------------------------------
function status(f) {
  if (!f) return '';
  const error = f.relErr ? `${(100 * Number(f.relErr)).toFixed(2)} %` : '–';
  return `${f.integrator} ${f.width}x${f.height}  ${f.spp} spp  ${f.elapsed.toFixed(2)} s  ` +
    `${(f.sps / 1e6).toFixed(2)} Msamples/s  est. rel. error ${error}${f.interactive ? '  (drag preview)' : ''}`;
}

// Relative MSE of A against B (the mean over pixels and channels of (a - b)^2 / (b^2 + eps),
// eps = (0.01 mean(b))^2, as niebla compare computes it).
function relativeMse(a, b) {
  if (!a || !b || a.width !== b.width || a.height !== b.height) return null;
  let mean = 0;
  for (let i = 0; i < b.halves.length; i++) mean += HALF[b.halves[i]];
  mean /= b.halves.length;
  const eps = Math.max((0.01 * mean) ** 2, 1e-30);
  let sum = 0;
  for (let i = 0; i < a.halves.length; i++) {
    const x = HALF[a.halves[i]], r = HALF[b.halves[i]];
    sum += (x - r) ** 2 / (r * r + eps);
  }
  return sum / a.halves.length;
}

const UNBIASED = { volpath: 'unbiased', ppm: 'consistent (converges to volpath)' };

function updateCompare() {
  const [a, b] = state.frames;
  if (!state.compare || !a || !b) { $('compare-status').textContent = ''; $('bias-note').textContent = ''; return; }
  state.relativeMse = relativeMse(a, b);
  const mse = state.relativeMse === null ? '–' : state.relativeMse.toExponential(3);
  $('compare-status').textContent = `B: ${status(b)}\nrelative MSE of A against B: ${mse}`;
  const kind = (name) => UNBIASED[name] ?? 'biased (its difference to volpath does not vanish with more samples)';
  $('bias-note').textContent = `A = ${a.integrator}: ${kind(a.integrator)}. B = ${b.integrator}: ${kind(b.integrator)}.`;
}

// One frame request of `slot` (long poll), started as soon as the previous
// answer's headers name its id, so the next frame's request travels while
// this one is decoded and drawn.
function requestFrame(slot) {
  const requested = performance.now();
  return fetch(`api/frame?slot=${slot}&after=${state.lastId[slot]}`)
    .then((response) => ({ response, requested, headersAt: performance.now() }));
}

// Milliseconds per stage from the server's X-Niebla-Timing header.
function serverTiming(value) {
  const stages = {};
  for (const pair of (value ?? '').split(';')) {
    const [name, ms] = pair.split('=');
    if (name) stages[name] = Number(ms);
  }
  return stages;
}

async function pollSlot(slot) {
  let next = null;
  for (;;) {
    if (slot === 1 && !state.compare) { next = null; await sleep(150); continue; }
    let reply;
    try {
      reply = await (next ?? requestFrame(slot));
    } catch (e) {
      next = null;
      $('status').textContent = 'disconnected; retrying';
      await sleep(1000);
      continue;
    }
    next = null;
    const { response, headersAt } = reply;
    const reloads = Number(response.headers.get('X-Niebla-Reloads') ?? 0);
    if (reloads !== state.reloads) {
      state.reloads = reloads;
      await loadState();
    }
    if (response.status === 204) continue;
    if (response.headers.get('X-Niebla-Event') === 'error') {
      const event = await response.json();
      state.lastId[slot] = event.id;
      showError(event.error);
      continue;
    }
    if (!response.ok) { await sleep(1000); continue; }
    const h = (name) => response.headers.get(`X-Niebla-${name}`);
    state.lastId[slot] = Number(h('Id'));
    next = requestFrame(slot);
    const halves = new Uint16Array(await response.arrayBuffer());
    const bodyAt = performance.now();
    const frame = {
      width: Number(h('Width')), height: Number(h('Height')), halves, spp: Number(h('Spp')),
      elapsed: Number(h('Elapsed')), sps: Number(h('Samples-Per-Second')), relErr: h('Relative-Error'),
      interactive: h('Interactive') === 'true', integrator: h('Integrator'), version: Number(h('Version')),
      receivedAt: bodyAt,
    };
    if (slot === 1 && !state.compare) continue;
    state.frames[slot] = frame;
    state.frameCount[slot] += 1;
    display.upload(slot, frame.width, frame.height, halves);
    const uploadedAt = performance.now();
    display.draw();
    const drawnAt = performance.now();
    if (slot === 0 && state.sentAt[frame.version] !== undefined) {
      const sent = state.sentAt[frame.version];
      const server = serverTiming(h('Timing'));
      // Edit to drawn frame, and where it went: the POST until the server had
      // it (network up), the server's stages, the way back until the page had
      // the headers (network down), the body, the texture upload and the draw.
      const timing = {
        post: state.postAt[frame.version] - sent, server, headers: headersAt - sent,
        body: bodyAt - headersAt, upload: uploadedAt - bodyAt, draw: drawnAt - uploadedAt,
      };
      timing.up = server.server !== undefined ? headersAt - sent - server.server : null;
      state.latencies.push({ version: frame.version, ms: drawnAt - sent, interactive: frame.interactive, timing });
      // Edits superseded before their first frame never get one.
      for (const v of Object.keys(state.sentAt)) if (Number(v) <= frame.version) { delete state.sentAt[v]; delete state.postAt[v]; }
    }
    if (slot === 0) $('status').textContent = status(frame);
    updateCompare();
  }
}

async function main() {
  try {
    display = new Display($('canvas'));
  } catch (e) {
    showError(String(e));
    return;
  }
  await loadState();
  wireControls();
  pollSlot(0);
  pollSlot(1);
}

main();
