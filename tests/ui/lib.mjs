// Reusable pieces of the teach UI browser tests: start a server program that prints JSON lines,
// launch Debian's chromium headless through playwright-core (never a downloaded browser), wait
// for events, and the standard page checks. teach_ui_browser_test.mjs uses them against
// ui_fake_session; an end-to-end test can use them against the real app and the mock robot.
//
// Server contract: the program prints, on stdout, once it serves the page, either
//   {"event":"listening","url":"http://127.0.0.1:PORT/"}
// or any line containing its loopback URL (http://127.0.0.1:PORT/, localhost, [::1]). Every
// stdout line is collected as an event: JSON objects as they are (e.g. {"event":"intent",...}),
// other lines as {"event":"text","text":...}.
import { spawn } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, rmSync, accessSync, constants } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { createInterface } from 'node:readline';
import { fileURLToPath } from 'node:url';

export const HERE = dirname(fileURLToPath(import.meta.url));
export const DEFAULT_CHROMIUM = '/usr/bin/chromium';

/// Chromium flags for a quiet, offline, throw-away browser (no sandbox: CI runs as root).
export const CHROMIUM_ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
];

/// Minimal "--key value" / "--flag" parser; repeated keys keep the last value.
export function parseArgs(argv, defaults = {}) {
  const out = { ...defaults };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (!a.startsWith('--')) throw new Error(`unexpected argument ${a}`);
    const key = a.slice(2);
    const next = argv[i + 1];
    if (next === undefined || next.startsWith('--') && !(key.endsWith('args'))) out[key] = true;
    else { out[key] = next; i++; }
  }
  return out;
}

/// Splits "a b 'c d'" into ['a', 'b', 'c d'] (single or double quotes, no escapes).
export function splitArgs(text) {
  if (!text || text === true) return [];
  const out = [];
  const re = /"([^"]*)"|'([^']*)'|(\S+)/g;
  let m;
  while ((m = re.exec(text)) !== null) out.push(m[1] ?? m[2] ?? m[3]);
  return out;
}

/// Fails loudly when the browser toolchain is missing: scripts/setup.sh installs it, so a missing
/// piece means the machine's setup is broken (we never skip).
export async function requireBrowserToolchain(chromiumPath = DEFAULT_CHROMIUM) {
  const problems = [];
  if (!existsSync(join(HERE, 'node_modules', 'playwright-core'))) {
    problems.push(`node module playwright-core missing in ${HERE}/node_modules (run scripts/setup.sh, `
      + 'which runs "npm ci" in tests/ui)');
  }
  try { accessSync(chromiumPath, constants.X_OK); } catch (e) {
    problems.push(`chromium not executable at ${chromiumPath} (Debian package "chromium"; `
      + 'run scripts/setup.sh)');
  }
  if (problems.length) throw new Error(`browser test setup is broken:\n  ${problems.join('\n  ')}`);
  const { chromium } = await import('playwright-core');
  return chromium;
}

/// Starts the server program; resolves once it printed its "listening" line.
export async function startServer(command, args = [], { startTimeoutMs = 20000, echo = false } = {}) {
  const proc = spawn(command, args, { stdio: ['pipe', 'pipe', 'pipe'] });
  const events = [];
  const waiters = new Set();
  let stderr = '';
  let exited = null;
  proc.stderr.on('data', (d) => { stderr += d.toString(); if (echo) process.stderr.write(d); });
  const rl = createInterface({ input: proc.stdout });
  rl.on('line', (line) => {
    let ev;
    try { ev = JSON.parse(line); } catch (e) { ev = { event: 'text', text: line }; }
    if (typeof ev !== 'object' || ev === null) ev = { event: 'text', text: line };
    ev._t = Date.now();
    events.push(ev);
    if (echo) console.log(`  server: ${line}`);
    for (const w of [...waiters]) w();
  });
  proc.on('exit', (code, signal) => {
    exited = { code, signal };
    for (const w of [...waiters]) w();
  });

  /// Resolves with the first event (from index `from` on) that satisfies `pred`.
  function waitForEvent(pred, { timeoutMs = 10000, from = 0, what = 'event' } = {}) {
    return new Promise((resolve, reject) => {
      let timer = null;
      const check = () => {
        for (let i = from; i < events.length; i++) {
          if (pred(events[i])) { cleanup(); resolve(events[i]); return; }
        }
        if (exited) { cleanup(); reject(new Error(`server exited (${JSON.stringify(exited)}) before ${what}; stderr:\n${stderr}`)); }
      };
      const cleanup = () => { waiters.delete(check); clearTimeout(timer); };
      timer = setTimeout(() => { cleanup(); reject(new Error(`timed out after ${timeoutMs} ms waiting for ${what}`)); }, timeoutMs);
      waiters.add(check);
      check();
    });
  }

  // The JSON "listening" line, or else any line (JSON or text, stdout) naming a loopback URL.
  const urlIn = (text) => {
    const m = /(http:\/\/(?:127\.0\.0\.1|localhost|\[::1\]):\d+\/?)/.exec(text || '');
    return m ? m[1] : null;
  };
  const first = await waitForEvent(
    (e) => (e.event === 'listening' && e.url) || urlIn(e.event === 'text' ? e.text : e.url),
    { timeoutMs: startTimeoutMs, what: 'the "listening" line (or a line with the page URL)' });
  const listening = { url: first.event === 'listening' && first.url ? first.url
    : urlIn(first.event === 'text' ? first.text : first.url) };

  async function stop() {
    if (exited) return exited;
    const done = new Promise((r) => proc.once('exit', () => r()));
    proc.stdin.end();  // servers started with --exit-on-stdin-eof stop here
    const t1 = setTimeout(() => proc.kill('SIGTERM'), 3000);
    const t2 = setTimeout(() => proc.kill('SIGKILL'), 8000);
    await done;
    clearTimeout(t1); clearTimeout(t2);
    return exited;
  }

  return { proc, url: listening.url, events, waitForEvent, stop, stderr: () => stderr };
}

/// Launches Debian's chromium headless with a fresh profile; returns { context, page, close }.
export async function launchBrowser({ chromiumPath = DEFAULT_CHROMIUM, viewport = { width: 1440, height: 960 } } = {}) {
  const chromium = await requireBrowserToolchain(chromiumPath);
  const userDataDir = mkdtempSync(join(tmpdir(), 'pepper-ui-chromium-'));
  // playwright passes the profile folder to chromium as --user-data-dir.
  const context = await chromium.launchPersistentContext(userDataDir, {
    executablePath: chromiumPath,
    headless: true,
    args: CHROMIUM_ARGS,
    viewport,
    offline: false,
  });
  const page = context.pages()[0] ?? await context.newPage();
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  async function close() {
    await context.close().catch(() => {});
    rmSync(userDataDir, { recursive: true, force: true });
  }
  return { context, page, close, consoleErrors };
}

export function ensureDir(p) { mkdirSync(p, { recursive: true }); return p; }

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/// Tiny test runner printing "N passed, N failed" at the end (a line CI understands).
export function makeRunner() {
  const results = [];
  async function step(name, fn) {
    const t0 = Date.now();
    try {
      const note = await fn();
      results.push({ name, ok: true });
      console.log(`ok   ${name} (${Date.now() - t0} ms)${note ? ` - ${note}` : ''}`);
    } catch (e) {
      results.push({ name, ok: false });
      console.log(`FAIL ${name} (${Date.now() - t0} ms)\n     ${String(e && e.stack || e).split('\n').join('\n     ')}`);
    }
  }
  function finish() {
    const passed = results.filter((r) => r.ok).length;
    const failed = results.length - passed;
    console.log(`${passed} passed, ${failed} failed`);
    return failed === 0 && passed > 0 ? 0 : 1;
  }
  return { step, finish, results };
}

// ------------------------------------------------------------------ standard page checks

/// The page connected its WebSocket (the UI pill says so).
export async function expectConnected(page, timeoutMs = 10000) {
  await page.waitForFunction(() => window.teachUi && window.teachUi.wsOpen === true, null, { timeout: timeoutMs });
}

/// The live image advances by at least `frames`; returns the measured display rate in fps.
export async function expectFramesAdvance(page, frames = 10, timeoutMs = 15000) {
  const n0 = await page.evaluate(() => window.teachUi.framesDrawn);
  const t0 = Date.now();
  await page.waitForFunction((target) => window.teachUi.framesDrawn >= target, n0 + frames, { timeout: timeoutMs, polling: 50 });
  const n1 = await page.evaluate(() => window.teachUi.framesDrawn);
  const counter = Number(await page.textContent('#frame-counter'));
  if (counter < n0 + frames) throw new Error(`frame counter shows ${counter}, expected >= ${n0 + frames}`);
  return (n1 - n0) * 1000 / (Date.now() - t0);
}

/// Holds `key` for `holdMs`, then releases it; `onHeld` / `onReleased` make the assertions (for
/// the fake session: an intent line; for the real app: the mock robot's motion).
export async function holdKey(page, key, holdMs, onHeld, onReleased) {
  await page.bringToFront();
  await page.locator('body').click({ position: { x: 5, y: 5 } });  // focus the page, not a control
  await page.keyboard.down(key);
  const held = await onHeld();
  await sleep(holdMs);
  await page.keyboard.up(key);
  const released = await onReleased();
  return { held, released };
}

/// Pixels of the live image (#camera canvas) that are clearly coloured: the camera image is grey,
/// so these are the drawn feature overlay (green lines, red points).
export async function overlayPixels(page) {
  return page.evaluate(() => {
    const c = document.getElementById('camera');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      const hi = Math.max(d[i], d[i + 1], d[i + 2]);
      const lo = Math.min(d[i], d[i + 1], d[i + 2]);
      if (hi - lo > 60) n += 1;
    }
    return n;
  });
}

/// Waits for a frame with feature overlay drawn (`need`: 'lines', 'points', 'both' or 'any'),
/// checks the canvas really has coloured pixels, then that unticking the "features" checkbox
/// removes them and ticking it brings them back. Returns a note with the counts.
export async function expectOverlayDrawn(page, { need = 'any', timeoutMs = 15000 } = {}) {
  await page.waitForFunction((what) => {
    const u = window.teachUi;
    const l = u.overlayLinesDrawn > 0; const p = u.overlayPointsDrawn > 0;
    return what === 'both' ? l && p : what === 'lines' ? l : what === 'points' ? p : l || p;
  }, need, { timeout: timeoutMs, polling: 50 });
  const counts = await page.evaluate(() => [window.teachUi.overlayLinesDrawn, window.teachUi.overlayPointsDrawn]);
  const on = await overlayPixels(page);
  if (on === 0) throw new Error(`page reports ${counts[0]} lines / ${counts[1]} points drawn but the canvas has no coloured pixel`);
  await page.uncheck('#show-features');
  const off = await overlayPixels(page);
  const offCounts = await page.evaluate(() => [window.teachUi.overlayLinesDrawn, window.teachUi.overlayPointsDrawn]);
  await page.check('#show-features');
  if (off !== 0 || offCounts[0] + offCounts[1] !== 0) {
    throw new Error(`with "features" unticked the canvas still has ${off} coloured pixels (${offCounts} drawn)`);
  }
  await page.waitForFunction(() => window.teachUi.overlayLinesDrawn + window.teachUi.overlayPointsDrawn > 0,
    null, { timeout: timeoutMs, polling: 50 });
  return `${counts[0]} lines, ${counts[1]} points drawn (${on} coloured pixels); none when unticked`;
}

/// Display rate of the live image over `seconds`: frames drawn and frames received per second,
/// from the page's own counters (window.teachUi), wall time measured in the page.
export async function measureFrameRate(page, seconds) {
  const read = () => page.evaluate(() => ({
    drawn: window.teachUi.framesDrawn, received: window.teachUi.framesReceived, t_ms: performance.now(),
  }));
  const a = await read();
  await sleep(seconds * 1000);
  const b = await read();
  const dt_s = (b.t_ms - a.t_ms) / 1000;
  return { drawn_fps: (b.drawn - a.drawn) / dt_s, received_fps: (b.received - a.received) / dt_s, seconds: dt_s };
}
