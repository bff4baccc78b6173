// Pepper teach & replay page logic. Plain JavaScript, no framework, no network beyond the
// WebSocket back to the server that served this page. Schema: docs/teach_ui.md.
//
// Safety rules implemented here (the server and the app add their own):
//  - driving needs a held key or button; the drive intent is refreshed every DRIVE_REFRESH_MS
//    while held, and releasing, losing focus, hiding the tab or losing the socket sends a stop;
//  - the space bar and the STOP button send an emergency stop at any time.
'use strict';

(() => {
  const DRIVE_REFRESH_MS = 100;
  const PING_PERIOD_MS = 1000;
  const KIND_FRAME = 1;
  const KIND_IMAGE = 2;
  const $ = (id) => document.getElementById(id);

  // Exposed for tests and debugging (read-only use).
  const ui = {
    framesReceived: 0,
    framesDrawn: 0,
    // Feature overlay of the image on screen: segments and points drawn (0 when hidden by the
    // "features" checkbox), and how many frames so far had any drawn.
    overlayLinesDrawn: 0,
    overlayPointsDrawn: 0,
    framesWithOverlay: 0,
    live: false,     // WebSocket to the app open
    lastSeq: 0,
    wsOpen: false,
    sent: [],        // last intents sent (type only), newest last
    state: {},
  };
  window.teachUi = ui;

  // ------------------------------------------------------------------ WebSocket
  let ws = null;
  let reconnectDelayMs = 500;
  let limits = { max_v_m_s: 0.35, max_omega_rad_s: 1.0 };

  function connect() {
    const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
    ws = new WebSocket(`${proto}//${location.host}/ws`);
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => {
      ui.wsOpen = true;
      reconnectDelayMs = 500;
      setLive(true);
      setPill('pill-ui', 'UI: connected', 'ok');
      logLine('connected to the app');
    };
    ws.onclose = () => {
      const was = ui.wsOpen;
      ui.wsOpen = false;
      setPill('pill-ui', 'UI: disconnected', 'bad');
      releaseAll('socket_closed', /*send=*/false);  // the server stops a driving client itself
      setLive(false);
      if (was) logLine('connection to the app lost; retrying');
      setTimeout(connect, reconnectDelayMs);
      reconnectDelayMs = Math.min(5000, reconnectDelayMs * 2);
    };
    ws.onmessage = (ev) => {
      if (typeof ev.data === 'string') onText(ev.data);
      else onBinary(ev.data);
    };
  }

  // Without the app nothing on the page is live: say so at once, disable the controls (except
  // STOP, which does no harm) and mark the live readings stale instead of leaving the last ones
  // looking current.
  const LIVE_IDS = ['m-fps', 'm-latency', 'm-rtt', 'pill-head', 'teach-kv', 'drive-readout'];
  function setLive(live) {
    ui.live = live;
    $('banner-offline').hidden = live;
    if (!live) $('teach-feedback').hidden = true;  // a live warning without the app is not live
    document.body.classList.toggle('offline', !live);
    document.querySelectorAll('.panel button, .pad-btn, #v-max, #w-max').forEach((b) => {
      b.disabled = !live;
    });
    for (const id of LIVE_IDS) $(id).classList.toggle('stale', !live);
    if (!live) {
      pendingFrame = null;
      frameTimes.length = 0;
      setPill('pill-robot', 'robot: unknown (app not connected)', 'bad');
      $('m-fps').textContent = '-- fps';
      $('m-latency').textContent = 'latency --';
      $('m-rtt').textContent = 'rtt --';
      $('drive-readout').textContent = 'idle';
    }
  }

  function send(obj) {
    if (!ws || ws.readyState !== WebSocket.OPEN) return false;
    ws.send(JSON.stringify(obj));
    ui.sent.push(obj.type);
    if (ui.sent.length > 50) ui.sent.shift();
    return true;
  }

  function onText(text) {
    let msg;
    try { msg = JSON.parse(text); } catch (e) { return; }
    switch (msg.type) {
      case 'hello':
        if (msg.limits) applyLimits(msg.limits);
        break;
      case 'state':
        Object.assign(ui.state, msg.state || {});
        renderState(msg.state || {});
        break;
      case 'samples':
        onSamples(msg);
        break;
      case 'pong':
        if (typeof msg.t_ms === 'number') {
          $('m-rtt').textContent = `rtt ${(performance.now() - msg.t_ms).toFixed(0)} ms`;
        }
        break;
      default:
        break;
    }
  }

  function onBinary(buf) {
    if (buf.byteLength < 5) return;
    const dv = new DataView(buf);
    const kind = dv.getUint8(0);
    const n = dv.getUint32(1, true);
    if (5 + n > buf.byteLength) return;
    let header;
    try { header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 5, n))); } catch (e) {
      return;
    }
    const bytes = new Uint8Array(buf, 5 + n);
    if (kind === KIND_FRAME) onFrame(header, bytes);
    else if (kind === KIND_IMAGE) onImage(header, bytes);
  }

  function mimeOf(bytes) {
    if (bytes.length > 3 && bytes[0] === 0x89 && bytes[1] === 0x50) return 'image/png';
    return 'image/jpeg';
  }

  // ------------------------------------------------------------------ camera
  const cam = $('camera');
  const camCtx = cam.getContext('2d');
  const showFeatures = $('show-features');
  let shown = null;  // { bmp, header } on screen, kept to redraw when the checkbox changes
  let decoding = false;
  let pendingFrame = null;
  const frameTimes = [];

  function onFrame(header, bytes) {
    ui.framesReceived += 1;
    pendingFrame = { header, bytes };  // latest wins while a decode is in progress
    if (!decoding) decodeNext();
  }

  async function decodeNext() {
    const f = pendingFrame;
    pendingFrame = null;
    if (!f) return;
    decoding = true;
    try {
      const bmp = await createImageBitmap(new Blob([f.bytes], { type: mimeOf(f.bytes) }));
      if (shown) shown.bmp.close();
      shown = { bmp, header: f.header };
      drawFrame(bmp, f.header);
    } catch (e) {
      logLine('could not decode a frame');
    }
    decoding = false;
    if (pendingFrame) decodeNext();
  }

  function render(bmp, header) {
    if (cam.width !== bmp.width || cam.height !== bmp.height) {
      cam.width = bmp.width;
      cam.height = bmp.height;
    }
    camCtx.drawImage(bmp, 0, 0);
    const ov = header.overlay || {};
    const sx = ov.width_px ? bmp.width / ov.width_px : 1;
    const sy = ov.height_px ? bmp.height / ov.height_px : 1;
    drawOverlay(ov, sx, sy);
  }

  showFeatures.addEventListener('change', () => { if (shown) render(shown.bmp, shown.header); });

  function drawFrame(bmp, header) {
    render(bmp, header);
    if (ui.overlayLinesDrawn + ui.overlayPointsDrawn > 0) ui.framesWithOverlay += 1;
    $('no-signal').hidden = true;
    ui.framesDrawn += 1;
    ui.lastSeq = header.seq || 0;
    $('frame-counter').textContent = String(ui.framesDrawn);
    // A frame decoded after the socket closed is the last image, not a live rate or latency.
    if (!ui.live) return;
    const now = performance.now();
    frameTimes.push(now);
    while (frameTimes.length && now - frameTimes[0] > 2000) frameTimes.shift();
    if (frameTimes.length > 1) {
      const fps = (frameTimes.length - 1) * 1000 / (now - frameTimes[0]);
      $('m-fps').textContent = `${fps.toFixed(1)} fps`;
    }
    if (typeof header.server_ms === 'number') {
      const lat = Date.now() - header.server_ms;
      const app = ui.state.camera && typeof ui.state.camera.latency_ms === 'number'
        ? ` + ${ui.state.camera.latency_ms.toFixed(0)}` : '';
      $('m-latency').textContent = `latency ${Math.max(0, lat).toFixed(0)}${app} ms`;
    }
  }

  // Lines and points are drawn only with the "features" checkbox ticked; the legend always
  // gives their counts.
  function drawOverlay(ov, sx, sy) {
    const lw = Math.max(1, cam.width / 320);
    const legend = [];
    const features = showFeatures.checked;
    ui.overlayLinesDrawn = 0;
    ui.overlayPointsDrawn = 0;
    for (const group of ov.lines || []) {
      const segments = group.segments || [];
      if (features) {
        camCtx.strokeStyle = group.color || '#22c55e';
        camCtx.lineWidth = (group.width_px || 2) * lw / 2;
        camCtx.beginPath();
        for (const s of segments) {
          camCtx.moveTo(s[0] * sx, s[1] * sy);
          camCtx.lineTo(s[2] * sx, s[3] * sy);
        }
        camCtx.stroke();
        ui.overlayLinesDrawn += segments.length;
      }
      if (group.label) legend.push([group.color || '#22c55e', group.label, segments.length]);
    }
    for (const group of ov.points || []) {
      const uv = group.uv || [];
      if (features) {
        camCtx.fillStyle = group.color || '#ef4444';
        const r = (group.radius_px || 3) * lw / 2;
        camCtx.beginPath();
        for (const p of uv) {
          camCtx.moveTo(p[0] * sx + r, p[1] * sy);
          camCtx.arc(p[0] * sx, p[1] * sy, r, 0, 2 * Math.PI);
        }
        camCtx.fill();
        ui.overlayPointsDrawn += uv.length;
      }
      if (group.label) legend.push([group.color || '#ef4444', group.label, uv.length]);
    }
    if (Array.isArray(ov.text) && ov.text.length) {
      camCtx.font = `${Math.round(12 * lw)}px sans-serif`;
      camCtx.fillStyle = 'rgba(0,0,0,0.55)';
      camCtx.fillRect(0, 0, cam.width, (ov.text.length * 16 + 6) * lw);
      camCtx.fillStyle = '#fff';
      ov.text.forEach((t, i) => camCtx.fillText(String(t), 6 * lw, (16 * i + 15) * lw));
    }
    const el = $('overlay-legend');
    el.replaceChildren(...legend.map(([color, label, count]) => {
      const span = document.createElement('span');
      const sw = document.createElement('i');
      sw.style.background = color;
      span.append(sw, `${label}: ${count}`);
      return span;
    }));
  }

  // ------------------------------------------------------------------ images (thumbnails)
  const images = new Map();  // name -> object URL

  function onImage(header, bytes) {
    const name = String(header.name || '');
    if (images.has(name)) URL.revokeObjectURL(images.get(name));
    if (bytes.length === 0) images.delete(name);
    else images.set(name, URL.createObjectURL(new Blob([bytes], { type: mimeOf(bytes) })));
    if (name.startsWith('key/')) renderStrip();
    const slot = { ip: 'img-ip', in: 'img-in', inn: 'img-inn' }[name];
    if (slot) {
      if (images.has(name)) $(slot).src = images.get(name);
      else $(slot).removeAttribute('src');
    }
  }

  function renderStrip() {
    const info = new Map();
    const teach = ui.state.teach || {};
    for (const k of teach.key_images || []) info.set(k.index, k);
    const indices = new Set([...info.keys()]);
    for (const name of images.keys()) {
      if (name.startsWith('key/')) indices.add(Number(name.slice(4)));
    }
    const sorted = [...indices].filter(Number.isFinite).sort((a, b) => a - b);
    const current = ui.state.replay ? ui.state.replay.key_index : undefined;
    const strip = $('key-strip');
    strip.replaceChildren(...sorted.map((i) => {
      const k = info.get(i) || {};
      const div = document.createElement('div');
      div.className = 'key' + (k.weak ? ' weak' : '') + (i === current ? ' current' : '');
      const img = document.createElement('img');
      if (images.has(`key/${i}`)) img.src = images.get(`key/${i}`);
      img.alt = `key image ${i}`;
      const cap = document.createElement('div');
      const feats = (k.n_lines !== undefined) ? ` · ${k.n_lines}L ${k.n_points}P` : '';
      cap.textContent = `#${i}${feats}`;
      div.title = k.weak ? 'too few features here' : '';
      div.append(img, cap);
      return div;
    }));
    $('key-count').textContent = String(sorted.length);
    if (sorted.length && current === undefined) strip.scrollLeft = strip.scrollWidth;
  }

  // ------------------------------------------------------------------ state rendering
  function setPill(id, text, cls) {
    const el = $(id);
    el.textContent = text;
    el.className = 'pill' + (cls ? ' ' + cls : '');
  }

  function fmt(x, digits = 2, unit = '') {
    return (typeof x === 'number' && Number.isFinite(x)) ? `${x.toFixed(digits)}${unit}` : '--';
  }

  function fillKv(id, pairs) {
    const dl = $(id);
    dl.replaceChildren();
    for (const [k, v] of pairs) {
      const dt = document.createElement('dt');
      dt.textContent = k;
      const dd = document.createElement('dd');
      dd.textContent = v;
      dl.append(dt, dd);
    }
  }

  let activeTabChosenByUser = false;
  const ROBOT_WARNING_SHOWN_MS = 10000;
  let robotWarningTimer = null;
  let lastRobotWarning = null;

  function renderState(patch) {
    const s = ui.state;
    if ('connection' in patch) {
      const c = s.connection || {};
      const robot = c.robot || 'unknown';
      setPill('pill-robot', `robot: ${robot}`,
        robot === 'connected' ? 'ok' : robot === 'connecting' ? 'warn' : 'bad');
      const head = c.head_locked;
      setPill('pill-head', `head: ${head === true ? 'locked' : head === false ? 'free' : '?'}`,
        head === true ? 'ok' : 'warn');
    }
    if ('mode' in patch) {
      // "replay on the mock" is a replay too: the replay panel, with the robot named.
      const on = s.robot_kind === 'mock' ? ' (simulated robot)' : '';
      setPill('pill-mode', `mode: ${s.mode || '?'}${on}`, 'mode');
      document.querySelectorAll('.tab').forEach((t) => {
        t.classList.toggle('live', t.dataset.tab === s.mode);
      });
      if (!activeTabChosenByUser && ['teach', 'replay', 'offline'].includes(s.mode)) {
        showTab(s.mode);
      }
    }
    if ('recording' in patch) {
      $('pill-rec').hidden = !s.recording;
      const b = $('btn-record');
      b.textContent = s.recording ? 'Stop recording' : 'Start recording';
      b.classList.toggle('recording', !!s.recording);
    }
    if ('robot_warning' in patch) {
      // The app reports a warning as long as it holds (checked every 0.5 s); one not renewed for
      // ROBOT_WARNING_SHOWN_MS is over and must not stay on screen as if it were current.
      const el = $('banner-robot-warning');
      clearTimeout(robotWarningTimer);
      el.hidden = !s.robot_warning;
      el.textContent = s.robot_warning
        ? `Robot warning (${new Date().toLocaleTimeString()}): ${s.robot_warning}` : '';
      if (s.robot_warning) {
        if (s.robot_warning !== lastRobotWarning) logLine(`robot warning: ${s.robot_warning}`);
        robotWarningTimer = setTimeout(() => { el.hidden = true; }, ROBOT_WARNING_SHOWN_MS);
      }
      lastRobotWarning = s.robot_warning;
    }
    if ('teach' in patch || 'warnings' in patch || 'drive' in patch) renderTeach();
    if ('teach_feedback' in patch) renderFeedback();
    if ('offline' in patch) drawTopView();
    if ('map_summary' in patch) renderSummary();
    if ('replay' in patch) renderReplay();
    if ('stop_reason' in patch || 'replay' in patch) renderStopReason();
    if ('trajectory' in patch || 'taught_path' in patch || 'floor_plan' in patch) drawTopView();
    if ('teach' in patch || 'replay' in patch) renderStrip();
  }

  // Why the session stopped. A replay that arrived at the end of its tour ended as it should:
  // "Finished", in green, not a red "Stopped" as for a fault (issue 30: what the operator sees is
  // true).
  function renderStopReason() {
    const s = ui.state;
    const r = s.replay || {};
    const arrived = r.outcome === 'tour_complete' && !!r.arrival && r.arrival.verdict === 'arrived';
    const el = $('stop-reason');
    el.hidden = !s.stop_reason;
    el.textContent = s.stop_reason ? `${arrived ? 'Finished' : 'Stopped'}: ${s.stop_reason}` : '';
    el.classList.toggle('ok', arrived);
  }

  function renderTeach() {
    const t = ui.state.teach || {};
    const d = ui.state.drive || {};
    const c = t.ceiling;  // ceiling mode: a mosaic instead of key images
    fillKv('teach-kv', c ? [
      ['relay images', 'chosen when the teach finishes'],
      ['distance (map)', fmt(t.distance_m, 2, ' m')],
      ['ceiling now', c.localised ? `${c.matched} landmarks matched, ${c.added} new`
        : 'no pose in the mosaic: drive back under mapped ceiling'],
      ['mosaic', `${c.mosaic_landmarks} landmarks, ${c.frames_without_pose} frames without a pose`
        + (c.loops_closed ? `, ${c.loops_closed} loops closed` : '')],
      ['command', `${fmt(d.v_m_s)} m/s, ${fmt(d.omega_rad_s)} rad/s`],
    ] : [
      ['key images', String((t.key_images || []).length)],
      ['distance (map)', fmt(t.distance_m, 2, ' m')],
      ['features now', t.n_lines !== undefined ? `${t.n_lines} lines, ${t.n_points} points` : '--'],
      ['command', `${fmt(d.v_m_s)} m/s, ${fmt(d.omega_rad_s)} rad/s`],
    ]);
    const warnings = [...(ui.state.warnings || [])];
    const weak = (t.key_images || []).filter((k) => k.weak).map((k) => `#${k.index}`);
    if (weak.length) warnings.push(`Too few features at key image(s) ${weak.join(', ')}`);
    $('teach-warnings').replaceChildren(...warnings.map((w) => {
      const li = document.createElement('li');
      li.textContent = w;
      return li;
    }));
  }

  // Live teach warnings: shown while the app reports them (it clears them itself, with a short
  // hold against blinking); a new kind is also written to the log once.
  let feedbackKinds = new Set();
  function renderFeedback() {
    const list = ((ui.state.teach_feedback || {}).warnings || []);
    const el = $('teach-feedback');
    el.hidden = list.length === 0;
    el.replaceChildren(...list.map((w) => {
      const li = document.createElement('li');
      li.className = `fb-${w.kind}`;
      li.dataset.kind = w.kind;
      li.textContent = w.text;
      return li;
    }));
    const kinds = new Set(list.map((w) => w.kind));
    for (const w of list) if (!feedbackKinds.has(w.kind)) logLine(`teach warning: ${w.text}`);
    feedbackKinds = kinds;
  }

  function renderSummary() {
    const m = ui.state.map_summary;
    const el = $('map-summary');
    el.hidden = !m;
    if (!m) return;
    el.replaceChildren();
    const h = document.createElement('h3');
    h.textContent = 'Map saved';
    const p = document.createElement('div');
    p.textContent = `${m.key_images} key images, ${fmt(m.length_m, 2, ' m')}, `
      + `min ${m.min_lines ?? '--'} lines / ${m.min_points ?? '--'} points per key image`;
    el.append(h, p);
    if (m.path) {
      const q = document.createElement('div');
      q.textContent = m.path;
      q.className = 'hint';
      el.append(q);
    }
    if (Array.isArray(m.weak_key_images) && m.weak_key_images.length) {
      const w = document.createElement('div');
      w.textContent = `Weak key images: ${m.weak_key_images.join(', ')} (re-teach these parts)`;
      w.style.color = 'var(--bad)';
      el.append(w);
    }
  }

  function renderReplay() {
    const r = ui.state.replay || {};
    const loc = r.localisation || {};
    const el = $('localisation');
    if (loc.ok === undefined) {  // never the replay state: that is in the progress line
      el.textContent = 'localisation: --';
      el.className = 'localisation';
    } else {
      el.textContent = `localisation: ${loc.ok ? 'OK' : 'failed'}`
        + (loc.key_index !== undefined ? ` at key image ${loc.key_index}` : '')
        + (loc.detail ? ` (${loc.detail})` : '');
      el.className = 'localisation ' + (loc.ok ? 'ok' : 'bad');
    }
    const k = r.key_index;
    const n = r.key_count;
    const frac = (typeof r.distance_m === 'number' && r.total_m > 0)
      ? r.distance_m / r.total_m : (n > 1 && typeof k === 'number' ? k / (n - 1) : 0);
    $('progress-bar').style.width = `${Math.max(0, Math.min(1, frac)) * 100}%`;
    // Key images are numbered 0..n-1, as on the console ("furthest key image 4 of 4").
    const last = typeof n === 'number' ? n - 1 : undefined;
    $('progress-text').textContent = `key image ${k ?? '--'} of ${last ?? '--'} · `
      + `${fmt(r.distance_m, 2)} / ${fmt(r.total_m, 2)} m · ${r.state || ''}`
      + (r.outcome ? ` (${r.outcome})` : '')
      + arrivalText(r.arrival);
  }

  // The replay's own verdict at the end of the tour (no ground truth): arrived / not aligned.
  function arrivalText(a) {
    if (!a || !a.verdict) return '';
    if (a.verdict === 'unknown') return ' · arrival unknown (no estimate)';
    const cm = typeof a.offset_m === 'number' ? `${(100 * a.offset_m).toFixed(0)} cm` : '--';
    return ` · ${a.verdict === 'arrived' ? 'arrived' : 'not aligned'}, ${cm} off (${a.source})`;
  }

  // ------------------------------------------------------------------ plots
  let samples = [];
  const MAX_SAMPLES = 2000;

  function onSamples(msg) {
    if (msg.reset) samples = [];
    for (const s of msg.samples || []) samples.push(s);
    if (samples.length > MAX_SAMPLES) samples = samples.slice(-MAX_SAMPLES);
    schedulePlots();
  }

  let plotQueued = false;
  function schedulePlots() {
    if (plotQueued) return;
    plotQueued = true;
    requestAnimationFrame(() => {
      plotQueued = false;
      drawPlot($('plot-cmd'), [
        ['v_m_s', 'v (m/s)', '#2563eb'],
        ['omega_rad_s', 'ω (rad/s)', '#f97316'],
      ]);
      // The counts the samples carry: lines and points, or in ceiling mode the landmarks the
      // mosaic kept (and, while teaching, the new ones it added).
      const has = (key) => samples.some((s) => typeof s[key] === 'number');
      drawPlot($('plot-feat'), has('ceiling_inliers')
        ? [['ceiling_inliers', 'ceiling landmarks', '#ef4444'],
          ['ceiling_added', 'new landmarks', '#f59e0b']].filter(([key]) => has(key))
        : [['n_lines', 'lines', '#16a34a'], ['n_points', 'points', '#9333ea']]);
    });
  }

  function drawPlot(canvas, series) {
    const ctx = canvas.getContext('2d');
    const W = canvas.width;
    const H = canvas.height;
    const L = 42; const R = 8; const T = 18; const B = 18;
    ctx.clearRect(0, 0, W, H);
    ctx.font = '11px sans-serif';
    const xs = samples.map((s) => (typeof s.t_s === 'number' ? s.t_s : s.distance_m));
    let lo = Infinity; let hi = -Infinity;
    for (const [key] of series) {
      for (const s of samples) {
        const v = s[key];
        if (typeof v === 'number' && Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
      }
    }
    if (!Number.isFinite(lo)) { lo = 0; hi = 1; }
    if (lo > 0) lo = 0;
    if (hi - lo < 1e-6) hi = lo + 1;
    const pad = (hi - lo) * 0.08;
    lo -= lo < 0 ? pad : 0; hi += pad;
    const x0 = xs.length ? Math.min(...xs.filter(Number.isFinite)) : 0;
    const x1 = xs.length ? Math.max(...xs.filter(Number.isFinite)) : 1;
    const px = (x) => L + (x1 > x0 ? (x - x0) / (x1 - x0) : 0) * (W - L - R);
    const py = (y) => T + (1 - (y - lo) / (hi - lo)) * (H - T - B);
    ctx.strokeStyle = '#e5e7eb';
    ctx.fillStyle = '#6b7280';
    ctx.lineWidth = 1;
    for (let i = 0; i <= 4; i++) {
      const y = lo + (hi - lo) * i / 4;
      ctx.beginPath(); ctx.moveTo(L, py(y)); ctx.lineTo(W - R, py(y)); ctx.stroke();
      ctx.fillText(Math.abs(hi - lo) >= 10 ? y.toFixed(0) : y.toFixed(2), 2, py(y) + 4);
    }
    if (lo < 0 && hi > 0) {
      ctx.strokeStyle = '#9ca3af';
      ctx.beginPath(); ctx.moveTo(L, py(0)); ctx.lineTo(W - R, py(0)); ctx.stroke();
    }
    const xLabel = samples.length && typeof samples[0].t_s === 'number' ? 't (s)' : 'distance (m)';
    ctx.fillStyle = '#6b7280';
    ctx.fillText(`${fmt(x0, 1)} … ${fmt(x1, 1)} ${xLabel}`, W - R - 130, H - 4);
    let lx = L;
    for (const [key, label, color] of series) {
      ctx.strokeStyle = color;
      ctx.lineWidth = 1.6;
      ctx.beginPath();
      let started = false;
      samples.forEach((s, i) => {
        const v = s[key];
        if (typeof v !== 'number' || !Number.isFinite(xs[i])) { started = false; return; }
        if (!started) ctx.moveTo(px(xs[i]), py(v)); else ctx.lineTo(px(xs[i]), py(v));
        started = true;
      });
      ctx.stroke();
      ctx.fillStyle = color;
      ctx.fillRect(lx, 5, 12, 3);
      ctx.fillStyle = '#374151';
      ctx.fillText(label, lx + 16, 11);
      lx += ctx.measureText(label).width + 36;
    }
  }

  // ------------------------------------------------------------------ offline top view
  const LABEL_GAP_PX = 16;
  const HOVER_RADIUS_PX = 9;
  let topViewKeys = [];  // key-image marks in canvas pixels: {index, x, y}

  // The key image under the pointer (nearest mark within HOVER_RADIUS_PX), shown with its
  // thumbnail (the `key/<index>` image the app sent) and its figures when known.
  function onTopViewHover(ev) {
    const canvas = $('topview');
    const r = canvas.getBoundingClientRect();
    const px = (ev.clientX - r.left) * canvas.width / r.width;
    const py = (ev.clientY - r.top) * canvas.height / r.height;
    let best = null; let bestD = HOVER_RADIUS_PX;
    for (const k of topViewKeys) {
      const d = Math.hypot(k.x - px, k.y - py);
      if (d <= bestD) { best = k; bestD = d; }
    }
    const tip = $('topview-tip');
    if (!best) { tip.hidden = true; ui.topViewHover = null; return; }
    const img = $('topview-tip-img');
    const src = images.get(`key/${best.index}`);
    if (src) img.src = src; else img.removeAttribute('src');
    const info = ((ui.state.teach || {}).key_images || []).find((k) => k.index === best.index) || {};
    const facts = info.n_lines !== undefined ? ` · ${info.n_lines} lines, ${info.n_points} points` : '';
    $('topview-tip-text').textContent = `key image ${best.index}${facts}${src ? '' : ' (no image)'}`;
    // Beside the mark, kept inside the canvas box.
    const cssX = best.x * r.width / canvas.width; const cssY = best.y * r.height / canvas.height;
    tip.hidden = false;
    tip.style.left = `${Math.min(cssX + 12, r.width - tip.offsetWidth)}px`;
    tip.style.top = `${Math.max(0, cssY - tip.offsetHeight - 8)}px`;
    ui.topViewHover = best.index;
  }

  function drawTopView() {
    const canvas = $('topview');
    const ctx = canvas.getContext('2d');
    const W = canvas.width; const H = canvas.height;
    ctx.clearRect(0, 0, W, H);
    const tr = ui.state.trajectory || {};
    const tp = ui.state.taught_path || {};  // constant part, sent once by the app
    const taught = tr.taught || tp.taught || []; const replayed = tr.replayed || [];
    const keys = tr.keys || tp.keys || [];
    const all = [...taught, ...replayed, ...keys];
    // The world's walls and furniture (simulated robot only), drawn under the paths. The view is
    // framed on the paths: a wall outside it is clipped (a large world does not shrink the tour).
    const plan = ui.state.floor_plan || {};
    const walls = plan.walls || []; const boxes = plan.boxes || [];
    if (!all.length) {
      topViewKeys = []; ui.topViewKeys = [];
      ctx.fillStyle = '#6b7280'; ctx.font = '13px sans-serif';
      ctx.fillText('no trajectory yet', 16, 24);
      return;
    }
    let xmin = Infinity; let xmax = -Infinity; let ymin = Infinity; let ymax = -Infinity;
    for (const [x, y] of all) {
      xmin = Math.min(xmin, x); xmax = Math.max(xmax, x);
      ymin = Math.min(ymin, y); ymax = Math.max(ymax, y);
    }
    const span = Math.max(xmax - xmin, ymax - ymin, 0.5) * 1.15;
    const cx = (xmin + xmax) / 2; const cy = (ymin + ymax) / 2;
    const scale = Math.min(W, H) / span;
    const tx = (x) => W / 2 + (x - cx) * scale;
    const ty = (y) => H / 2 - (y - cy) * scale;  // world y up on screen
    // 0.5 m grid
    ctx.strokeStyle = '#f1f5f9'; ctx.lineWidth = 1;
    const step = span > 10 ? 2 : 0.5;
    for (let g = Math.floor((cx - span) / step) * step; g < cx + span; g += step) {
      ctx.beginPath(); ctx.moveTo(tx(g), 0); ctx.lineTo(tx(g), H); ctx.stroke();
    }
    for (let g = Math.floor((cy - span) / step) * step; g < cy + span; g += step) {
      ctx.beginPath(); ctx.moveTo(0, ty(g)); ctx.lineTo(W, ty(g)); ctx.stroke();
    }
    ctx.strokeStyle = '#9ca3af'; ctx.lineWidth = 1;
    for (const corners of boxes) {
      ctx.beginPath();
      corners.forEach(([x, y], i) => (i ? ctx.lineTo(tx(x), ty(y)) : ctx.moveTo(tx(x), ty(y))));
      ctx.closePath(); ctx.stroke();
    }
    ctx.strokeStyle = '#374151'; ctx.lineWidth = 3;
    for (const [ax, ay, bx, by] of walls) {
      ctx.beginPath(); ctx.moveTo(tx(ax), ty(ay)); ctx.lineTo(tx(bx), ty(by)); ctx.stroke();
    }
    const path = (pts, color, width, dash) => {
      if (pts.length < 2) return;
      ctx.strokeStyle = color; ctx.lineWidth = width; ctx.setLineDash(dash);
      ctx.beginPath();
      pts.forEach(([x, y], i) => (i ? ctx.lineTo(tx(x), ty(y)) : ctx.moveTo(tx(x), ty(y))));
      ctx.stroke(); ctx.setLineDash([]);
    };
    // Key images under the paths: dense key images (every few cm) must not hide the paths.
    ctx.fillStyle = '#111827';
    for (const [x, y] of keys) { ctx.beginPath(); ctx.arc(tx(x), ty(y), 3.5, 0, 2 * Math.PI); ctx.fill(); }
    path(taught, '#2563eb', 3, []);
    path(replayed, '#f97316', 2, [6, 4]);
    // Their numbers (the key image's index, as on the console and in the strip) beside the marks,
    // over the paths; where marks crowd, only those at least LABEL_GAP_PX from the last number
    // drawn get one (hovering any mark still shows it).
    topViewKeys = keys.map(([x, y], i) => ({ index: i, x: tx(x), y: ty(y) }));
    ctx.font = 'bold 11px sans-serif'; ctx.textBaseline = 'bottom';
    let lastLabel = null;
    for (const k of topViewKeys) {
      if (lastLabel && Math.hypot(k.x - lastLabel.x, k.y - lastLabel.y) < LABEL_GAP_PX
          && k.index !== topViewKeys.length - 1) continue;
      const label = String(k.index);
      const w = ctx.measureText(label).width;
      ctx.fillStyle = 'rgba(255,255,255,0.85)';
      ctx.fillRect(k.x + 4, k.y - 16, w + 4, 13);
      ctx.fillStyle = '#111827';
      ctx.fillText(label, k.x + 6, k.y - 3);
      lastLabel = k;
    }
    ctx.textBaseline = 'alphabetic';
    ui.topViewKeys = topViewKeys;
    // Where the replay drove on odometry alone (vision blind): red dots over the replayed path.
    const blind = tr.blind || [];
    ctx.fillStyle = '#dc2626';
    for (const [x, y] of blind) { ctx.beginPath(); ctx.arc(tx(x), ty(y), 3, 0, 2 * Math.PI); ctx.fill(); }
    ctx.fillStyle = '#6b7280'; ctx.font = '11px sans-serif';
    ctx.fillText(`grid ${step} m`, 8, H - 8);
    const o = ui.state.offline || {};
    fillKv('offline-kv', [
      ['taught', `${taught.length} poses`],
      ['replayed', `${replayed.length} poses`],
      ['on odometry alone (red)', `${blind.length} poses`],
      // Lateral error needs ground truth: the simulated robot has it, a real one does not.
      ['max lateral error', lateral(o.max_lateral_error_m)],
      ['mean lateral error', lateral(o.mean_lateral_error_m)],
    ]);
  }

  function lateral(x) {
    if (ui.state.robot_kind === 'real') return 'needs ground truth (simulated robot only)';
    return typeof x === 'number' ? `${x.toFixed(3)} m (ground truth)` : '--';
  }

  // ------------------------------------------------------------------ driving (dead-man)
  const held = { up: false, down: false, left: false, right: false };
  let driving = false;
  let refreshTimer = null;
  const KEYMAP = {
    ArrowUp: 'up', KeyW: 'up', ArrowDown: 'down', KeyS: 'down',
    ArrowLeft: 'left', KeyA: 'left', ArrowRight: 'right', KeyD: 'right',
  };

  function applyLimits(l) {
    limits = { ...limits, ...l };
    const v = $('v-max'); const w = $('w-max');
    v.max = String(limits.max_v_m_s);
    w.max = String(limits.max_omega_rad_s);
    if (Number(v.value) > limits.max_v_m_s) v.value = String(limits.max_v_m_s);
    if (Number(w.value) > limits.max_omega_rad_s) w.value = String(limits.max_omega_rad_s);
    showLimits();
  }
  function showLimits() {
    $('v-max-label').textContent = `${Number($('v-max').value).toFixed(2)} m/s`;
    $('w-max-label').textContent = `${Number($('w-max').value).toFixed(2)} rad/s`;
  }

  function command() {
    const vmax = Number($('v-max').value);
    const wmax = Number($('w-max').value);
    const v = ((held.up ? 1 : 0) - (held.down ? 1 : 0)) * vmax;
    const omega = ((held.left ? 1 : 0) - (held.right ? 1 : 0)) * wmax;  // > 0 turns left
    return { v, omega };
  }

  function updateDrive(reason) {
    const { v, omega } = command();
    document.querySelectorAll('.pad-btn').forEach((b) => {
      b.classList.toggle('held', !!held[b.dataset.dir]);
    });
    const readout = $('drive-readout');
    if (v !== 0 || omega !== 0) {
      send({ type: 'drive', v_m_s: v, omega_rad_s: omega });
      driving = true;
      readout.textContent = `${v.toFixed(2)} m/s ${omega.toFixed(2)} rad/s`;
      readout.classList.add('driving');
      if (!refreshTimer) {
        refreshTimer = setInterval(() => {
          const c = command();
          if (c.v !== 0 || c.omega !== 0) send({ type: 'drive', v_m_s: c.v, omega_rad_s: c.omega });
        }, DRIVE_REFRESH_MS);
      }
    } else {
      stopRefresh();
      readout.textContent = 'idle';
      readout.classList.remove('driving');
      if (driving) {
        driving = false;
        send({ type: 'drive_released', reason });
      }
    }
  }
  function stopRefresh() {
    if (refreshTimer) { clearInterval(refreshTimer); refreshTimer = null; }
  }
  function releaseAll(reason, sendIt = true) {
    for (const k of Object.keys(held)) held[k] = false;
    if (!sendIt) { driving = false; }
    updateDrive(reason);
  }

  function emergencyStop(reason) {
    for (const k of Object.keys(held)) held[k] = false;
    stopRefresh();
    driving = false;
    updateDrive(reason);
    send({ type: 'estop', reason });
    const b = $('estop');
    b.classList.add('fired');
    setTimeout(() => b.classList.remove('fired'), 600);
    logLine(`emergency stop (${reason})`);
  }

  function isTextField(el) {
    return el && (el.tagName === 'TEXTAREA' || (el.tagName === 'INPUT' && el.type === 'text'));
  }

  window.addEventListener('keydown', (ev) => {
    if (isTextField(ev.target)) return;
    if (ev.code === 'Space') {
      ev.preventDefault();
      if (!ev.repeat) emergencyStop('space');
      return;
    }
    const dir = KEYMAP[ev.code];
    if (!dir) return;
    ev.preventDefault();  // no scrolling, no slider changes
    if (ev.repeat || held[dir]) return;
    held[dir] = true;
    updateDrive('key');
  }, true);
  window.addEventListener('keyup', (ev) => {
    // Space is the emergency stop only: a focused button or checkbox must not also act on it
    // (they activate on keyup).
    if (ev.code === 'Space' && !isTextField(ev.target)) { ev.preventDefault(); return; }
    const dir = KEYMAP[ev.code];
    if (!dir) return;
    ev.preventDefault();
    held[dir] = false;
    updateDrive('key_released');
  }, true);
  window.addEventListener('blur', () => releaseAll('blur'));
  document.addEventListener('visibilitychange', () => {
    if (document.hidden) releaseAll('hidden');
  });

  document.querySelectorAll('.pad-btn').forEach((b) => {
    const dir = b.dataset.dir;
    const press = (ev) => {
      ev.preventDefault();
      b.setPointerCapture?.(ev.pointerId);
      held[dir] = true;
      updateDrive('button');
    };
    const release = () => {
      if (!held[dir]) return;
      held[dir] = false;
      updateDrive('button_released');
    };
    b.addEventListener('pointerdown', press);
    b.addEventListener('pointerup', release);
    b.addEventListener('pointercancel', release);
    b.addEventListener('lostpointercapture', release);
    b.addEventListener('contextmenu', (ev) => ev.preventDefault());
  });

  // On pointerdown (the earliest moment), and on a keyboard click (Enter on the focused button).
  $('estop').addEventListener('pointerdown', () => emergencyStop('button'));
  $('estop').addEventListener('click', (ev) => { if (ev.detail === 0) emergencyStop('button'); });
  $('btn-record').addEventListener('click', () => {
    send({ type: ui.state.recording ? 'stop_recording' : 'start_recording' });
  });
  $('btn-finish').addEventListener('click', () => send({ type: 'finish_teach' }));
  $('btn-replay').addEventListener('click', () => send({ type: 'start_replay' }));
  $('topview').addEventListener('mousemove', onTopViewHover);
  $('topview').addEventListener('mouseleave', () => { $('topview-tip').hidden = true; ui.topViewHover = null; });
  $('v-max').addEventListener('input', showLimits);
  $('w-max').addEventListener('input', showLimits);

  // ------------------------------------------------------------------ tabs, log, ping
  function showTab(name) {
    document.querySelectorAll('.tab').forEach((t) => t.classList.toggle('active', t.dataset.tab === name));
    for (const p of ['teach', 'replay', 'offline']) $(`panel-${p}`).hidden = p !== name;
    if (name === 'replay') schedulePlots();
    if (name === 'offline') drawTopView();
  }
  document.querySelectorAll('.tab').forEach((t) => t.addEventListener('click', () => {
    activeTabChosenByUser = true;
    showTab(t.dataset.tab);
  }));

  const logLines = [];
  function logLine(text) {
    const t = new Date().toLocaleTimeString();
    logLines.push(`${t}  ${text}`);
    if (logLines.length > 3) logLines.shift();
    $('log').textContent = logLines.join('\n');
  }

  setInterval(() => {
    if (ws && ws.readyState === WebSocket.OPEN) {
      ws.send(JSON.stringify({ type: 'ping', t_ms: performance.now() }));
    }
  }, PING_PERIOD_MS);

  showLimits();
  setLive(false);
  renderTeach();
  drawTopView();
  schedulePlots();
  connect();
})();
