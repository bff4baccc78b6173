// End-to-end browser test of the real app (issue 6): `pepper_app teach` and `pepper_app replay`
// on the in-process mock robot with the teach UI, driven by Debian's chromium through
// playwright-core (tests/ui/lib.mjs). Checks: the page loads and connects, the live image
// advances with the detected (teach) or matched (replay) lines and points drawn over it, holding
// the Up arrow makes the mock robot move (with `--events -` the app writes every base command as a
// JSON line on stdout: {"event":"command","v_m_s":...,"stop":false}) and releasing it stops it, the Finish
// button ends the teach with a saved map, the replay's top view draws the taught path (from the
// map's taught_path.json) and the replayed one, and STOP stops a running replay.
// It also measures the frame rate of the live image in the browser over --fps-seconds (default
// 10) of the teach session and --replay-fps-seconds (default 5) of the replay, and reports them;
// it asserts only >= --min-fps (default 5), a floor a loaded CI machine still reaches.
// Screenshots go to --artifacts (git-ignored).
//
//   node tests/ui/app_e2e_test.mjs --app build-app/pepper_app/pepper_app \
//        --world worlds/robotics_room.yaml [--artifacts tests/ui/artifacts] [--echo]
//        [--fps-seconds 10] [--replay-fps-seconds 5] [--min-fps 5]
import { spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import {
  HERE, parseArgs, startServer, launchBrowser, ensureDir, makeRunner, expectConnected,
  expectFramesAdvance, expectOverlayDrawn, measureFrameRate, holdKey, sleep,
} from './lib.mjs';

const opts = parseArgs(process.argv.slice(2), {
  app: join(HERE, '..', '..', 'build', 'pepper_app', 'pepper_app'),
  world: join(HERE, '..', '..', 'worlds', 'robotics_room.yaml'),
  artifacts: join(HERE, 'artifacts'),
  'fps-seconds': '10',
  'replay-fps-seconds': '5',
  'min-fps': '5',
});
const echo = opts.echo === true;
const QVGA = ['--set', 'robot.camera_width_px=320', '--set', 'robot.camera_height_px=240'];
const artifacts = ensureDir(opts.artifacts);
const work = mkdtempSync(join(tmpdir(), 'pepper-app-e2e-'));
const run = makeRunner();

const isCommand = (pred) => (e) => e.event === 'command' && pred(e);

/// Measures the page's display rate over `seconds`, prints it, fails below --min-fps.
async function checkFrameRate(page, seconds, what) {
  const r = await measureFrameRate(page, seconds);
  const note = `${r.drawn_fps.toFixed(1)} frames/s drawn, ${r.received_fps.toFixed(1)} received `
    + `over ${r.seconds.toFixed(1)} s (${what}, mock robot)`;
  console.log(`measured: ${note}`);
  if (!(r.drawn_fps >= Number(opts['min-fps']))) throw new Error(`${note}; expected >= ${opts['min-fps']}`);
  return note;
}

async function teachStep() {
  const server = await startServer(opts.app, ['teach', '--robot', `mock:${opts.world}`,
    '--map', join(work, 'ui_map'), '--manual', '--ui-port', '0', '--events', '-', ...QVGA], { echo });
  const browser = await launchBrowser();
  const { page } = browser;
  try {
    await run.step('teach page loads and connects', async () => {
      await page.goto(server.url);
      await expectConnected(page);
    });
    await run.step('live image from the mock robot advances', async () => {
      const fps = await expectFramesAdvance(page, 8);
      return `${fps.toFixed(1)} frames/s drawn`;
    });
    await run.step('detected lines and points are drawn over the live image', async () => (
      expectOverlayDrawn(page, { need: 'both' })));
    await run.step('frame rate of the live image in the browser (teach)', async () => (
      checkFrameRate(page, Number(opts['fps-seconds']), 'teach')));
    await run.step('holding Up moves the mock robot, releasing it stops it', async () => {
      let from = server.events.length;
      const r = await holdKey(page, 'ArrowUp', 800,
        () => server.waitForEvent(isCommand((e) => !e.stop && e.v_m_s > 0),
          { from, what: 'a forward base command' }),
        () => {
          from = server.events.length;
          return server.waitForEvent(isCommand((e) => e.stop), { from, what: 'a stop command' });
        });
      return `drove at ${r.held.v_m_s} m/s, then stop (${r.released.why})`;
    });
    await run.step('holding Left turns the mock robot left', async () => {
      const from = server.events.length;
      await holdKey(page, 'ArrowLeft', 400,
        () => server.waitForEvent(isCommand((e) => !e.stop && e.omega_rad_s > 0),
          { from, what: 'a left-turn command' }),
        () => server.waitForEvent(isCommand((e) => e.stop),
          { from: server.events.length, what: 'a stop command' }));
    });
    await run.step('screenshot of the live teach page', async () => {
      await sleep(300);
      const file = join(artifacts, 'app_teach.png');
      await page.screenshot({ path: file, fullPage: true });
      return file;
    });
    await run.step('Finish ends the teach with a saved map', async () => {
      await page.click('#btn-finish');
      const done = await server.waitForEvent((e) => e.event === 'teach_done',
        { timeoutMs: 30000, what: 'teach_done' });
      if (done.outcome !== 'finished' || !done.map_saved) throw new Error(JSON.stringify(done));
    });
  } finally {
    await browser.close();
    await server.stop();
  }
}

async function replayStep() {
  // A scripted tour to replay (no browser needed for it), long enough to be still driving at the
  // end of the frame-rate measurement.
  const mapDir = join(work, 'tour');
  const t = spawnSync(opts.app, ['teach', '--robot', `mock:${opts.world}`, '--map', mapDir,
    '--max-distance', '4.0', ...QVGA], { encoding: 'utf8' });
  if (t.status !== 0) throw new Error(`scripted teach failed:\n${t.stderr}`);
  if (!existsSync(join(mapDir, 'taught_path.json'))) throw new Error('teach on the mock wrote no taught_path.json');
  const server = await startServer(opts.app, ['replay', '--robot', `mock:${opts.world}`,
    '--map', mapDir, '--ui-port', '0', '--events', '-', '--mock-start', '0', '--seed', '0', ...QVGA], { echo });
  const browser = await launchBrowser();
  const { page } = browser;
  try {
    await run.step('replay page connects and the robot drives by itself', async () => {
      await page.goto(server.url);
      await expectConnected(page);
      await server.waitForEvent(isCommand((e) => !e.stop && e.v_m_s > 0),
        { timeoutMs: 30000, what: 'the navigator driving' });
      await expectFramesAdvance(page, 5);
    });
    await run.step('a replay on the mock robot shows the replay panel and says it is simulated', async () => {
      // Issue 30: it used to open on the Offline tab with "mode: offline".
      const pill = await page.textContent('#pill-mode');
      if (!pill.includes('replay (simulated robot)')) throw new Error(`mode pill: "${pill}"`);
      if (await page.isHidden('#panel-replay')) throw new Error('the replay panel is hidden');
      return pill;
    });
    await run.step('matched lines and points are drawn over the live image', async () => (
      expectOverlayDrawn(page, { need: 'any' })));
    await run.step('frame rate of the live image in the browser (replay)', async () => {
      const note = await checkFrameRate(page, Number(opts['replay-fps-seconds']), 'replay');
      const done = server.events.find((e) => e.event === 'replay_done');
      if (done) throw new Error(`the replay ended (${done.outcome}) during the measurement: ${note}`);
      return note;
    });
    await run.step('top view shows the taught and the replayed paths', async () => {
      await page.waitForFunction(() => {
        const s = window.teachUi.state;
        return s.taught_path && s.taught_path.taught.length >= 10
          && s.trajectory && s.trajectory.replayed.length >= 30;  // 2 s of replay
      }, null, { timeout: 15000, polling: 100 });
      // Pixels of the taught (blue #2563eb) and replayed (orange #f97316) polylines.
      const px = await page.evaluate(() => {
        const c = document.getElementById('topview');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let blue = 0; let orange = 0;
        for (let i = 0; i < d.length; i += 4) {
          if (d[i + 2] > 180 && d[i] < 90) blue += 1;
          if (d[i] > 200 && d[i + 1] > 80 && d[i + 1] < 160 && d[i + 2] < 60) orange += 1;
        }
        const s = window.teachUi.state;
        return { blue, orange, taught: s.taught_path.taught.length, keys: s.taught_path.keys.length };
      });
      if (px.blue === 0 || px.orange === 0) throw new Error(`top view pixels ${JSON.stringify(px)}`);
      return `taught ${px.taught} poses, ${px.keys} key images; ${px.blue} blue / ${px.orange} orange px`;
    });
    await run.step('screenshot of the replay page', async () => {
      const file = join(artifacts, 'app_replay.png');
      await page.screenshot({ path: file, fullPage: true });
      return file;
    });
    await run.step('STOP stops the replay', async () => {
      const from = server.events.length;
      await page.click('#estop');
      const done = await server.waitForEvent((e) => e.event === 'replay_done',
        { from, timeoutMs: 10000, what: 'replay_done' });
      if (done.outcome !== 'ui_stop') throw new Error(`outcome ${done.outcome}`);
      await server.waitForEvent(isCommand((e) => e.stop), { from, what: 'a stop command' });
    });
  } finally {
    await browser.close();
    await server.stop();
  }
}

try {
  if (!existsSync(opts.app)) throw new Error(`no app binary at ${opts.app} (--app)`);
  await run.step('teach session in the browser', teachStep);
  await run.step('replay session in the browser', replayStep);
} catch (e) {
  console.log(`FAIL setup: ${e.stack || e}`);
}
rmSync(work, { recursive: true, force: true });
process.exit(run.finish());
