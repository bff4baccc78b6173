// Browser test of the teach's live warnings (issue 25, "teach feedback that prevents a bad map"):
// `pepper_app teach --manual` on the mock robot in tests/ui/worlds/blank_wall_room.yaml, with the
// page in headless chromium. The robot starts facing a bookshelf: no warning. Turning left (Left
// arrow held) brings the bare north wall into view: the few-features warning must appear under
// the camera image, say what to do, and the app must report it in its events. Turning back
// (Right arrow held) to the shelves: it must go away. Screenshot:
// tests/ui/artifacts/teach_feedback_blank_wall.png.
//
//   node tests/ui/teach_feedback_test.mjs --app build/pepper_app/pepper_app \
//        [--world tests/ui/worlds/blank_wall_room.yaml] [--artifacts tests/ui/artifacts] [--echo]
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import {
  HERE, parseArgs, startServer, launchBrowser, ensureDir, makeRunner, expectConnected,
  expectFramesAdvance, sleep,
} from './lib.mjs';

const opts = parseArgs(process.argv.slice(2), {
  app: join(HERE, '..', '..', 'build', 'pepper_app', 'pepper_app'),
  world: join(HERE, 'worlds', 'blank_wall_room.yaml'),
  artifacts: join(HERE, 'artifacts'),
});
const echo = opts.echo === true;
const QVGA = ['--set', 'robot.camera_width_px=320', '--set', 'robot.camera_height_px=240'];
const artifacts = ensureDir(opts.artifacts);
const work = mkdtempSync(join(tmpdir(), 'pepper-teach-feedback-'));
const run = makeRunner();

/// The warnings shown under the camera image: [{kind, text}], empty when hidden.
const shownWarnings = (page) => page.evaluate(() => {
  const el = document.getElementById('teach-feedback');
  if (el.hidden) return [];
  return [...el.querySelectorAll('li')].map((li) => ({ kind: li.dataset.kind, text: li.textContent }));
});

/// Holds `key` until `pred(page)` is true in the page (or `timeoutMs`), then releases it.
async function turnUntil(page, key, pred, timeoutMs, what) {
  await page.bringToFront();
  await page.locator('body').click({ position: { x: 5, y: 5 } });  // focus the page, not a control
  await page.keyboard.down(key);
  try {
    await page.waitForFunction(pred, null, { timeout: timeoutMs, polling: 50 });
  } catch (e) {
    throw new Error(`${what}: not seen within ${timeoutMs} ms of holding ${key}`);
  } finally {
    await page.keyboard.up(key);
  }
}

const fewShown = () => {
  const el = document.getElementById('teach-feedback');
  return !el.hidden && !!el.querySelector('li[data-kind="few_features"]');
};
const noneShown = () => document.getElementById('teach-feedback').hidden;
// Shown and the bare wall really in view (a passing dip while turning also warns, for a moment).
const fewShownFacingBare = () => {
  const t = window.teachUi.state.teach || {};
  const el = document.getElementById('teach-feedback');
  return !el.hidden && !!el.querySelector('li[data-kind="few_features"]') && t.n_lines + t.n_points < 40;
};

async function main() {
  const server = await startServer(opts.app, ['teach', '--robot', `mock:${opts.world}`,
    '--map', join(work, 'map'), '--manual', '--ui-port', '0', '--events', '-', ...QVGA], { echo });
  const browser = await launchBrowser();
  const { page } = browser;
  try {
    await run.step('facing the bookshelf: features in view, no warning', async () => {
      await page.goto(server.url);
      await expectConnected(page);
      await expectFramesAdvance(page, 10);
      const t = await page.evaluate(() => window.teachUi.state.teach || {});
      if (!(t.n_lines + t.n_points >= 40)) throw new Error(`features now ${t.n_lines} + ${t.n_points}`);
      const w = await shownWarnings(page);
      if (w.length) throw new Error(`warnings shown: ${JSON.stringify(w)}`);
      return `${t.n_lines} lines, ${t.n_points} points`;
    });
    let appeared = null;
    await run.step('turning to the bare wall: the few-features warning appears and says what to do', async () => {
      const from = server.events.length;
      await turnUntil(page, 'ArrowLeft', fewShownFacingBare, 20000, 'the few-features warning facing the bare wall');
      await page.waitForFunction(fewShown, null, { timeout: 5000 });  // and still shown once stopped
      const w = await shownWarnings(page);
      const few = w.find((x) => x.kind === 'few_features');
      if (!/poster/.test(few.text) || !/needs \d+/.test(few.text)) throw new Error(`text "${few.text}"`);
      // The app said so in its events (the console stays quiet): the warning came, with its text
      // (the page's text follows the live count of features in view).
      const ev = await server.waitForEvent((e) => e.event === 'teach_feedback'
        && (e.warnings || []).some((x) => x.kind === 'few_features'), { from, what: 'a teach_feedback event' });
      const evText = ev.warnings.find((x) => x.kind === 'few_features').text;
      const shape = /^Few features in view: \d+ lines \+ points, a key image needs 40\. .*poster/;
      if (!shape.test(evText) || !shape.test(few.text)) throw new Error(`event "${evText}", page "${few.text}"`);
      const t = await page.evaluate(() => window.teachUi.state.teach || {});
      if (!(t.n_lines + t.n_points < 50)) throw new Error(`warning shown with ${t.n_lines} + ${t.n_points} features in view`);
      await page.screenshot({ path: join(artifacts, 'teach_feedback_blank_wall.png') });
      appeared = few.text;
      return few.text;
    });
    await run.step('turning back to the shelves: the warning goes away', async () => {
      if (!appeared) throw new Error('no warning appeared before');
      await turnUntil(page, 'ArrowRight', noneShown, 30000, 'the warnings cleared');
      await sleep(1000);  // and it stays away while the view is rich
      const w = await shownWarnings(page);
      if (w.length) throw new Error(`warnings back: ${JSON.stringify(w)}`);
      const t = await page.evaluate(() => window.teachUi.state.teach || {});
      if (!(t.n_lines + t.n_points >= 40)) throw new Error(`cleared with only ${t.n_lines} + ${t.n_points} features`);
      return `${t.n_lines} lines, ${t.n_points} points in view`;
    });
    await run.step('Finish: the session ends and no warning is left as live', async () => {
      await page.click('#btn-finish');
      const done = await server.waitForEvent((e) => e.event === 'teach_done', { timeoutMs: 30000, what: 'teach_done' });
      await page.waitForFunction(noneShown, null, { timeout: 10000 });
      // One event per change of the warnings, not one per frame.
      const changes = server.events.filter((e) => e.event === 'teach_feedback').length;
      const shown = done.warning_frames || {};
      if (!(shown.few_features > 0)) throw new Error(`teach_done.warning_frames ${JSON.stringify(shown)}`);
      if (changes > 20) throw new Error(`${changes} teach_feedback events`);
      return `${changes} teach_feedback events; frames shown ${JSON.stringify(shown)}`;
    });
  } finally {
    await browser.close();
    await server.stop();
    rmSync(work, { recursive: true, force: true });
  }
  process.exit(run.finish());
}

main().catch((e) => { console.error(e); process.exit(1); });
