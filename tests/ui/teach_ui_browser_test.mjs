#!/usr/bin/env node
// Browser test of the teach UI page: Debian's chromium, headless, driven by playwright-core,
// against a server program that logs every operator intent as a JSON line (ui_fake_session).
//
//   node tests/ui/teach_ui_browser_test.mjs --server build/teach_ui/ui_fake_session \
//        --server-args "--web-root teach_ui/web --exit-on-stdin-eof" [--artifacts DIR]
//        [--chromium /usr/bin/chromium] [--replay-scenario-args "--scenario replay"] [--echo]
//
// Checks: the page loads and connects; the live image updates (frame counter advances) with the
// feature overlay drawn over it (coloured pixels; none with "features" unticked); holding
// the Up arrow sends a drive intent and releasing it a drive_released; clicking STOP sends an
// estop; the space bar sends an estop; with a finished tour (--scenario replay) the key-image
// strip, progress and plots show; a robot warning the app reports shows in a banner (and the
// event log) and the banner goes when the app clears it. Screenshots go to --artifacts (git-ignored). Prints
// "N passed, N failed"; exit status 1 on any failure or when the toolchain is missing.
import { join } from 'node:path';
import {
  HERE, parseArgs, splitArgs, requireBrowserToolchain, startServer, launchBrowser, ensureDir,
  makeRunner, expectConnected, expectFramesAdvance, expectOverlayDrawn, holdKey,
} from './lib.mjs';

const opts = parseArgs(process.argv.slice(2), {
  artifacts: join(HERE, 'artifacts'),
  chromium: '/usr/bin/chromium',
  'replay-scenario-args': '--scenario replay',
});

async function main() {
  if (!opts.server || opts.server === true) {
    console.error('usage: teach_ui_browser_test.mjs --server PROGRAM [--server-args "..."]');
    return 2;
  }
  const run = makeRunner();
  try {
    await requireBrowserToolchain(opts.chromium);
  } catch (e) {
    console.log(`FAIL browser toolchain\n     ${e.message}`);
    console.log('0 passed, 1 failed');
    return 1;
  }
  const artifacts = ensureDir(opts.artifacts);
  const baseArgs = splitArgs(opts['server-args']);

  // ---------------------------------------------------------------- teach session
  let server = null;
  let browser = null;
  try {
    server = await startServer(opts.server, [...baseArgs, '--scenario', 'teach'], { echo: !!opts.echo });
    browser = await launchBrowser({ chromiumPath: opts.chromium });
    const { page } = browser;
    const intentAfter = (from, pred, what) => server.waitForEvent(
      (e) => e.event === 'intent' && pred(e), { from, what, timeoutMs: 10000 });

    await run.step('page loads and connects', async () => {
      const res = await page.goto(server.url, { waitUntil: 'load' });
      if (!res || res.status() !== 200) throw new Error(`GET ${server.url} gave ${res && res.status()}`);
      const title = await page.title();
      if (!title.includes('Pepper')) throw new Error(`unexpected title "${title}"`);
      await expectConnected(page);
      return `title "${title}"`;
    });

    await run.step('live image updates (frame counter advances)', async () => {
      const fps = await expectFramesAdvance(page, 20);
      return `${fps.toFixed(1)} frames/s displayed`;
    });

    await run.step('feature overlay is drawn over the live image and can be hidden', async () => (
      expectOverlayDrawn(page, { need: 'both' })));

    await run.step('holding Up sends a drive intent, releasing it sends a stop', async () => {
      const from = server.events.length;
      let drive = null;
      const { released } = await holdKey(page, 'ArrowUp', 400,
        async () => { drive = await intentAfter(from, (e) => e.kind === 'drive', 'a drive intent'); return drive; },
        async () => intentAfter(from, (e) => e.kind === 'drive_released', 'a drive_released intent'));
      if (!(drive.v_m_s > 0) || drive.omega_rad_s !== 0) throw new Error(`drive was ${JSON.stringify(drive)}`);
      if (released.reason !== 'key_released') throw new Error(`release reason ${released.reason}`);
      // No drive intent may follow the release (the refresh timer must have stopped).
      const idx = server.events.indexOf(released);
      await new Promise((r) => setTimeout(r, 300));
      const late = server.events.slice(idx + 1).filter((e) => e.event === 'intent' && e.kind === 'drive');
      if (late.length) throw new Error(`${late.length} drive intent(s) after the release`);
      return `v=${drive.v_m_s} m/s`;
    });

    await run.step('Left arrow turns left (omega > 0)', async () => {
      const from = server.events.length;
      let drive = null;
      await holdKey(page, 'ArrowLeft', 200,
        async () => { drive = await intentAfter(from, (e) => e.kind === 'drive', 'a drive intent'); },
        async () => intentAfter(from, (e) => e.kind === 'drive_released', 'a drive_released intent'));
      if (!(drive.omega_rad_s > 0) || drive.v_m_s !== 0) throw new Error(`drive was ${JSON.stringify(drive)}`);
    });

    await run.step('losing focus while driving sends a stop', async () => {
      const from = server.events.length;
      await page.keyboard.down('KeyW');
      await intentAfter(from, (e) => e.kind === 'drive', 'a drive intent');
      await page.evaluate(() => window.dispatchEvent(new Event('blur')));
      const stop = await intentAfter(from, (e) => e.kind === 'drive_released', 'a drive_released intent');
      await page.keyboard.up('KeyW');
      if (stop.reason !== 'blur') throw new Error(`release reason ${stop.reason}`);
    });

    await run.step('record button starts recording, key images appear', async () => {
      const from = server.events.length;
      await page.click('#btn-record');
      await intentAfter(from, (e) => e.kind === 'start_recording', 'a start_recording intent');
      await page.waitForSelector('#pill-rec:not([hidden])', { timeout: 10000 });
      await page.waitForFunction(() => document.querySelectorAll('#key-strip .key img[src]').length >= 2,
        null, { timeout: 15000 });
    });

    await run.step('clicking STOP sends an emergency stop', async () => {
      const from = server.events.length;
      await page.click('#estop');
      const e = await intentAfter(from, (ev) => ev.kind === 'estop', 'an estop intent');
      await page.waitForFunction(() => document.getElementById('stop-reason').textContent.includes('emergency'),
        null, { timeout: 10000 });
      return `reason ${e.reason}`;
    });

    await run.step('space bar sends an emergency stop', async () => {
      const from = server.events.length;
      await page.keyboard.press('Space');
      const e = await intentAfter(from, (ev) => ev.kind === 'estop', 'an estop intent');
      if (e.reason !== 'space') throw new Error(`reason ${e.reason}`);
    });

    await run.step('screenshot of the teach panel', async () => {
      await page.click('#btn-finish');
      await page.waitForSelector('#map-summary:not([hidden])', { timeout: 10000 });
      const file = join(artifacts, 'teach_ui_teach.png');
      await page.screenshot({ path: file, fullPage: true });
      return file;
    });

    await run.step('page raised no script errors', async () => {
      if (browser.consoleErrors.length) throw new Error(browser.consoleErrors.join('\n'));
    });
  } catch (e) {
    await run.step('teach session setup', async () => { throw e; });
  } finally {
    if (browser) await browser.close();
    if (server) await server.stop();
  }

  // ---------------------------------------------------------------- finished tour (replay view)
  server = null;
  browser = null;
  try {
    // The fake app reports a robot warning (MoveFailed) from 2 s for 4 s, then clears it.
    server = await startServer(opts.server, [...baseArgs, ...splitArgs(opts['replay-scenario-args']),
      '--robot-warning-at-s', '2', '--robot-warning-for-s', '4'], { echo: !!opts.echo });
    browser = await launchBrowser({ chromiumPath: opts.chromium });
    const { page } = browser;
    await page.goto(server.url, { waitUntil: 'load' });
    await expectConnected(page);

    await run.step('robot warning banner shows while the app reports one, and goes when it ends', async () => {
      await page.waitForSelector('#banner-robot-warning:not([hidden])', { timeout: 10000 });
      const text = await page.textContent('#banner-robot-warning');
      if (!/Robot warning .*MoveFailed/.test(text)) throw new Error(`banner reads "${text}"`);
      const file = join(artifacts, 'teach_ui_robot_warning.png');
      await page.screenshot({ path: file, fullPage: true });
      await page.waitForSelector('#banner-robot-warning[hidden]', { state: 'attached', timeout: 10000 });
      const log = await page.textContent('body');
      if (!/robot warning: MoveFailed/.test(log)) throw new Error('the warning is not in the event log');
      return file;
    });

    await run.step('replay view shows key strip, progress, thumbnails and plots', async () => {
      await page.waitForFunction(() => document.querySelectorAll('#key-strip .key img[src]').length === 12,
        null, { timeout: 10000 });
      // 12 key images, numbered 0..11 as on the app's console ("key image K of 11").
      await page.waitForFunction(() => /of 11/.test(document.getElementById('progress-text').textContent),
        null, { timeout: 10000 });
      await page.waitForSelector('#img-in[src]', { timeout: 10000 });
      await expectFramesAdvance(page, 10);
      const weak = await page.locator('#key-strip .key.weak').count();
      if (weak !== 1) throw new Error(`expected 1 weak key image marked, got ${weak}`);
      const file = join(artifacts, 'teach_ui_replay.png');
      await page.screenshot({ path: file, fullPage: true });
      return file;
    });

    await run.step('offline view draws the top view', async () => {
      await page.click('.tab[data-tab="offline"]');
      await page.waitForSelector('#panel-offline:not([hidden])');
      const file = join(artifacts, 'teach_ui_offline.png');
      await page.screenshot({ path: file, fullPage: true });
      const painted = await page.evaluate(() => {
        const c = document.getElementById('topview');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let blue = 0; let red = 0; let wall = 0;
        for (let i = 0; i < d.length; i += 4) {
          if (d[i + 2] > 200 && d[i] < 80) blue++;
          if (d[i] > 200 && d[i + 1] < 60 && d[i + 2] < 60) red++;  // #dc2626: driven blind
          // #374151: the floor plan's walls
          if (Math.abs(d[i] - 55) < 8 && Math.abs(d[i + 1] - 65) < 8 && Math.abs(d[i + 2] - 81) < 8) wall++;
        }
        return { blue, red, wall };
      });
      if (painted.wall < 100) throw new Error(`the floor plan's walls are not drawn (${painted.wall} px)`);
      if (painted.blue < 50) throw new Error(`taught path not drawn (${painted.blue} blue pixels)`);
      if (painted.red < 20) throw new Error(`the blind stretch is not drawn (${painted.red} red pixels)`);
      return file;
    });

    await run.step('top view: key images are numbered marks, hovering one shows its thumbnail', async () => {
      const keys = await page.evaluate(() => window.teachUi.topViewKeys || []);
      if (keys.length !== 12) throw new Error(`expected 12 key-image marks, got ${keys.length}`);
      const box = await page.locator('#topview').boundingBox();
      const size = await page.evaluate(() => [document.getElementById('topview').width,
        document.getElementById('topview').height]);
      const at = (k) => [box.x + k.x * box.width / size[0], box.y + k.y * box.height / size[1]];
      // Away from every mark: no thumbnail.
      await page.mouse.move(box.x + 3, box.y + 3);
      if (!(await page.isHidden('#topview-tip'))) throw new Error('a thumbnail is shown away from the marks');
      const seen = [];
      for (const i of [3, 11]) {
        const [x, y] = at(keys[i]);
        await page.mouse.move(x, y);
        await page.waitForSelector('#topview-tip:not([hidden])', { timeout: 3000 });
        const tip = await page.evaluate(() => {
          const img = document.getElementById('topview-tip-img');
          return { text: document.getElementById('topview-tip-text').textContent, src: img.getAttribute('src'),
            loaded: img.complete && img.naturalWidth > 0, hover: window.teachUi.topViewHover };
        });
        // The thumbnail is the key image's own (the `key/<i>` image the strip shows too).
        const stripSrc = await page.getAttribute(`#key-strip .key:nth-child(${i + 1}) img`, 'src');
        if (tip.hover !== i || !tip.text.startsWith(`key image ${i} `)) throw new Error(`hovering mark ${i}: ${JSON.stringify(tip)}`);
        if (!tip.src || tip.src !== stripSrc) throw new Error(`mark ${i} shows ${tip.src}, the strip's key image ${i} is ${stripSrc}`);
        await page.waitForFunction(() => {
          const img = document.getElementById('topview-tip-img'); return img.complete && img.naturalWidth > 0;
        }, null, { timeout: 3000 });
        seen.push(tip.text);
      }
      await page.screenshot({ path: join(artifacts, 'teach_ui_topview_hover.png'), fullPage: true });
      await page.mouse.move(box.x + box.width + 40, box.y);  // off the canvas
      await page.waitForSelector('#topview-tip', { state: 'hidden', timeout: 3000 });
      // The numbers are drawn: dark text pixels beside mark 0 (none of the paths is that dark).
      const dark = await page.evaluate((k) => {
        const c = document.getElementById('topview');
        const d = c.getContext('2d').getImageData(Math.round(k.x + 4), Math.round(k.y - 16), 12, 13).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (d[i] < 60 && d[i + 1] < 60 && d[i + 2] < 60) n++;
        return n;
      }, keys[0]);
      if (dark < 5) throw new Error(`no number drawn beside key image 0 (${dark} dark pixels)`);
      return seen.join('; ');
    });

    await run.step('replay page raised no script errors', async () => {
      if (browser.consoleErrors.length) throw new Error(browser.consoleErrors.join('\n'));
    });
  } catch (e) {
    await run.step('replay session setup', async () => { throw e; });
  } finally {
    if (browser) await browser.close();
    if (server) await server.stop();
  }
  return run.finish();
}

main().then((code) => process.exit(code), (e) => {
  console.error(e);
  console.log('0 passed, 1 failed');
  process.exit(1);
});
