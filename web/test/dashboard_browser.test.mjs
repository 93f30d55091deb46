// The dashboard in a real browser (Debian's chromium, driven by puppeteer-core from npm): starts
// `phri run --dashboard` on the simulated arm in real time, opens the printed address with its
// token and checks, as a user would see it, that
//   1. the plots advance (the x axis follows robot time, redrawn at >= 30 Hz);
//   2. the full-body compliance button switches the mode, and the log downloaded from the page
//      records the switch (compliance_mode column);
//   3. dragging the end-effector link pushes the arm: the streamed end effector moves, the push
//      shown never exceeds the cap;
//   4. moving the stiffness slider applies the new gain (streamed and logged stiffness_scale);
//   5. the power-and-force-limiting bars show one number per monitored link;
//   6. a push held still for 5 s while the page is slowed 4x (CPU throttling: long tasks of hundreds
//      of ms) stays on the arm without a gap in the log (live_push_n) beyond what late renewals explain
//      (each renewal's send and reply times come back from the worker); long tasks and plot rate printed.
// Screenshots go to --out (dashboard_*.png). Exit 77 (ctest: skipped) when chromium is absent.
//
//   node web/test/dashboard_browser.test.mjs --phri build/release/phri --config configs/dashboard.yaml --out DIR
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { setTimeout as sleep } from 'node:timers/promises';

const args = Object.fromEntries(process.argv.slice(2).reduce((pairs, a, i, all) =>
  (a.startsWith('--') ? [...pairs, [a.slice(2), all[i + 1]]] : pairs), []));
const chromium = ['/usr/bin/chromium', '/usr/bin/chromium-browser'].find((p) => fs.existsSync(p));
if (!chromium) {
  console.log('SKIPPED: Debian chromium is not installed (/usr/bin/chromium); scripts/setup installs it');
  process.exit(77);
}
const puppeteer = (await import('puppeteer-core')).default;
const out = path.resolve(args.out || 'dashboard_browser');
fs.mkdirSync(out, { recursive: true });

let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
}

// phri, until it prints the dashboard's address.
// On a small machine the browser (software WebGL) competes with the 1 kHz loop, whose policy is a safe
// hold after two overruns in a row: phri runs its loop under SCHED_FIFO where allowed, and the
// browser runs at nice +15 (below).
function startPhri() {
  const child = spawn(args.phri, ['run', '--config', args.config, '--realtime', '--dashboard', '--port', '0',
                                  '--out', out, '--duration', '300', '--no-figure', '--log', 'csv'], { stdio: ['ignore', 'pipe', 'pipe'] });
  let text = '';
  child.stderr.on('data', (d) => process.stderr.write(d));
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error('phri printed no dashboard address in 30 s:\n' + text)), 30000);
    child.stdout.on('data', (d) => {
      text += d;
      for (const line of String(d).split('\n')) if (/SAFE|safety:|cycles,/.test(line)) console.log('phri: ' + line);
      const m = text.match(/phri dashboard: (http:\/\/\S+)/);
      if (m) { clearTimeout(timer); resolve({ child, url: m[1] }); }
    });
    child.on('exit', (code) => reject(new Error(`phri exited (${code}) before serving:\n${text}`)));
  });
}

async function waitFor(page, fn, what, timeout = 20000, arg = undefined) {
  try {
    await page.waitForFunction(fn, { timeout, polling: 50 }, arg);
    return true;
  } catch {
    check(false, `${what} (waited ${timeout / 1000} s)`);
    return false;
  }
}

// The log behind the page's "download log" link (fetched here, not in the page: it grows by
// ~1 MB a second), as rows of numbers by column name.
async function downloadLog(page) {
  const href = await page.$eval('#log', (a) => a.href);
  const csv = await (await fetch(href)).text();
  const lines = csv.trim().split('\n');
  const header = lines[0].split(',');
  const rows = lines.slice(1).map((l) => l.split(',').map(Number));
  return { column: (name) => rows.map((r) => r[header.indexOf(name)]), rows: rows.length, header };
}

const { child, url } = await startPhri();
console.log('phri serves ' + url.replace(/token=.*/, 'token=…'));
const browser = await puppeteer.launch({
  executablePath: chromium, headless: true,
  // WebGL through SwiftShader (no GPU here); 2-D canvases (the plots) in software: SwiftShader's
  // accelerated 2-D canvas stalled the page for 0.5 s at a time on this 2-core machine.
  args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--disable-accelerated-2d-canvas',
         '--window-size=1400,1300'],
});
spawnSync('renice', ['-n', '15', '-g', String(browser.process().pid)], { stdio: 'ignore' });
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 1300 });
  page.setDefaultNavigationTimeout(120000);  // a loaded 2-core machine (the browser runs at nice 15) needs more than 30 s
  page.on('pageerror', (e) => check(false, 'page error: ' + e.message));

  // Without the token: refused.
  const refused = await page.goto(url.replace(/\?token=.*/, ''));
  check(refused.status() === 401, `the page without its token is refused (HTTP ${refused.status()})`);

  await page.goto(url);
  await waitFor(page, () => window.phri && window.phri.frames > 20, 'frames stream in');
  // 1. The plots advance, redrawn at >= 30 Hz.
  const before = await page.evaluate(() => ({ x: window.phri.plotXMax(), n: window.phri.plotUpdates, t: performance.now() }));
  await sleep(2000);
  const after = await page.evaluate(() => ({ x: window.phri.plotXMax(), n: window.phri.plotUpdates, t: performance.now() }));
  const rate = (after.n - before.n) / ((after.t - before.t) / 1000);
  check(after.x > before.x + 1.5, `plots advance with robot time (${before.x?.toFixed(2)} s -> ${after.x?.toFixed(2)} s)`);
  check(rate >= 30, `plots redrawn at ${rate.toFixed(1)} Hz (>= 30)`);
  await waitFor(page, () => window.phri.last.fsm === 'static', 'start-up ends (static scenario)', 30000);
  // The loop's button is highlighted under the name the stream gives the loop (custom, position, ...).
  await waitFor(page, () => {
    const on = [...document.querySelectorAll('#events-loop button.active')].map((b) => b.id);
    return on.length === 1 && on[0] === `event-${window.phri.last.loop}_loop`;
  }, 'the running loop\'s button, and only it, is highlighted');
  await page.screenshot({ path: path.join(out, 'dashboard_start.png') });

  // 2. Full-body compliance from its button, found in the log.
  const modeBefore = await page.evaluate(() => window.phri.last.mode);
  await page.click('#event-full_body_compliance');
  await waitFor(page, () => window.phri.last.mode === 'full_body', 'the stream shows full-body compliance');
  await sleep(300);  // the log writer flushes every few ms
  const log = await downloadLog(page);
  const modes = log.column('compliance_mode');
  const legend = fs.readFileSync(path.join(out, 'phri_dashboard.legend.yaml'), 'utf8');
  const fullBody = Number((legend.match(/compliance_mode:[\s\S]*?(\d+): full_body/) || [])[1]);
  check(modeBefore !== 'full_body' && modes.includes(fullBody) && modes[0] !== fullBody && modes.at(-1) === fullBody,
        `the downloaded log (${log.rows} rows) records the switch ${modeBefore} -> full_body (code ${fullBody})`);

  // 3. Drag the end-effector link: the arm moves in the streamed state.
  await sleep(1000);
  const ee = await page.evaluate(() => window.phri.capsuleIndex('end_effector_link'));
  const start = await page.evaluate((i) => window.phri.screenOfCapsule(i), ee);
  const p0 = await page.evaluate(() => window.phri.last.ee.p);
  await page.evaluate(() => { window.phri.maxPush = 0; window.phri.maxMove = 0; });
  await page.evaluate((p) => {  // the largest push and end-effector displacement the stream shows
    window.phri.track = setInterval(() => {
      const f = window.phri.last;
      if (f.push) window.phri.maxPush = Math.max(window.phri.maxPush, f.push.magnitude);
      window.phri.maxMove = Math.max(window.phri.maxMove, Math.hypot(...f.ee.p.map((v, i) => v - p[i])));
    }, 10);
  }, p0);
  await page.mouse.move(start.x, start.y);
  await page.mouse.down();
  for (let k = 1; k <= 10; ++k) { await page.mouse.move(start.x + 6 * k, start.y + 2 * k); await sleep(30); }
  await sleep(800);
  await page.screenshot({ path: path.join(out, 'dashboard_push.png') });
  const shown = await page.evaluate(() => document.getElementById('push-readout').textContent);
  await page.mouse.up();
  await sleep(500);
  const pushed = await page.evaluate(() => { clearInterval(window.phri.track); return [window.phri.maxPush, window.phri.maxMove]; });
  check(/pushing .*: \d+(\.\d)? N/.test(shown), `the page shows the push: "${shown}"`);
  check(pushed[0] > 5 && pushed[0] <= 100 + 1e-6, `the stream shows the push, at most the 100 N cap (max ${pushed[0].toFixed(1)} N)`);
  check(pushed[1] > 0.02, `dragging the end effector moved it ${(1e3 * pushed[1]).toFixed(0)} mm (> 20 mm)`);
  // 5. a bar per monitored link, its number the streamed v / v_max (the push moved the arm).
  const bars = await page.evaluate(() => ({
    rows: [...document.querySelectorAll('#contact .contact-row')].map((r) => r.children[2].textContent),
    links: window.phri.model.contact.length,
    streamed: window.phri.last.contact_ratio,
  }));
  check(bars.links > 0 && bars.rows.length === bars.links && bars.streamed.length === bars.links &&
        bars.rows.every((text, i) => text === bars.streamed[i].toFixed(2)),
        `a power-and-force-limiting bar per link (${bars.rows.length} of ${bars.links}: ${bars.rows.join(' ')})`);
  await waitFor(page, () => window.phri.last.push === null, 'letting go ends the push', 3000);

  // 6. A push held for 5 s on a page slowed 4x (CPU throttling): the log shows it without a gap
  //    (renewed from a worker, whatever the page's main thread is doing); long tasks and plot rate printed.
  await page.evaluate(() => {
    window.phri.longTasks = [];
    window.phri.renewals = [];
    new PerformanceObserver((list) => window.phri.longTasks.push(...list.getEntries().map((e) => e.duration)))
      .observe({ type: 'longtask' });
  });
  const cdp = await page.target().createCDPSession();
  // Grab the link where it is now and drag; a loaded 2-core machine (the browser at nice 15) may take
  // seconds to take the drag in, or the link may have moved under the pointer: up to three tries.
  let started = false, heldFrom = 0, plotsBefore = 0;
  for (let attempt = 0; attempt < 3 && !started; ++attempt) {
    const grab = await page.evaluate((i) => window.phri.screenOfCapsule(i), ee);
    plotsBefore = await page.evaluate(() => window.phri.plotUpdates);
    heldFrom = Date.now();
    await page.mouse.move(grab.x, grab.y);
    await page.mouse.down();
    for (let k = 1; k <= 5; ++k) { await page.mouse.move(grab.x + 6 * k, grab.y + 2 * k); await sleep(30); }
    started = await page.waitForFunction(() => window.phri.last.push !== null && window.phri.last.push.magnitude > 5,
                                         { timeout: 10000 }).then(() => true, () => false);
    if (!started) { await page.mouse.up(); await sleep(1000); }
  }
  check(started, 'the held push starts');
  await cdp.send('Emulation.setCPUThrottlingRate', { rate: 4 });  // then the page slows down, the hand still
  const fromT = await page.evaluate(() => window.phri.last.t);
  await sleep(5000);
  const toT = await page.evaluate(() => window.phri.last.t);
  await page.mouse.up();
  const heldS = (Date.now() - heldFrom) / 1000;
  const plotsAfter = await page.evaluate(() => window.phri.plotUpdates);
  await cdp.send('Emulation.setCPUThrottlingRate', { rate: 1 });
  await sleep(1500);  // the push ends; the log writer flushes
  const held = await downloadLog(page);
  const times = held.column('time_s'), pushN = held.column('live_push_n');
  let rows = 0, gap = 0, run = 0;  // within the stream's times seen while the mouse was down
  for (let i = 0; i < times.length; ++i) {
    if (times[i] < fromT || times[i] > toT) continue;
    ++rows;
    if (pushN[i] > 0) { gap = Math.max(gap, run); run = 0; } else { ++run; }
  }
  gap = Math.max(gap, run);
  const tasks = await page.evaluate(() => window.phri.longTasks);
  // The server receives renewal i between its send s_i and its reply r_i, so two renewals arrive at
  // most r_{i+1} - s_i apart. The hold (0.5 s of robot time, which runs no faster than the wall
  // clock) ends the push only if that exceeds 500 ms, and then for at most the excess: a gap beyond
  // 50 ms plus the renewals' own lateness is the dashboard's fault, not the machine's.
  const renewals = await page.evaluate(() => window.phri.renewals);
  let late = 0, failed = 0;
  for (let i = 0; i + 1 < renewals.length; ++i) {
    if (renewals[i + 1][1] === null) { ++failed; continue; }
    late = Math.max(late, renewals[i + 1][1] - renewals[i][0] - 500);
  }
  const allowed = 50 + Math.max(0, late);
  console.log(`held push on a 4x-throttled page: ${heldS.toFixed(1)} s held, ${tasks.length} long tasks ` +
              `(${tasks.reduce((a, b) => a + b, 0).toFixed(0)} ms), plots redrawn at ${((plotsAfter - plotsBefore) / heldS).toFixed(1)} Hz, ` +
              `${renewals.length} renewals (${failed} failed), the latest ${Math.max(0, late).toFixed(0)} ms beyond the 500 ms hold`);
  check(rows >= 3000 && renewals.length >= 10 && failed === 0 && gap <= allowed,
        `the held push is in the log over ${(rows / 1000).toFixed(2)} s of robot time, longest gap ${gap} ms ` +
        `(<= 50${late > 0 ? ` + ${late.toFixed(0)} ms the renewals came late: a starved machine` : ''})`);

  // 4. The stiffness slider: drag its thumb to about 60 % of the range.
  const slider = await page.$('#gain-stiffness_scale');
  const box = await slider.boundingBox();
  await page.mouse.click(box.x + 0.6 * box.width, box.y + box.height / 2);
  const wanted = await page.evaluate(() => Number(document.getElementById('gain-stiffness_scale').value));
  await waitFor(page, (v) => Math.abs(window.phri.last.gains.stiffness_scale - v) < 1e-9,
                `the stream shows stiffness_scale ${wanted.toFixed(3)}`, 5000, wanted);
  await sleep(300);
  const scales = (await downloadLog(page)).column('stiffness_scale');
  check(Math.abs(wanted - 2.44) < 0.2 && Math.abs(scales.at(-1) - wanted) < 1e-6,
        `the slider set stiffness_scale ${wanted.toFixed(3)}; the log's last row has ${scales.at(-1)}`);
  await sleep(500);
  await page.screenshot({ path: path.join(out, 'dashboard_end.png') });

  // Stop from the page: phri brakes, holds and exits.
  await page.click('#event-stop');
  const code = await Promise.race([new Promise((r) => child.on('exit', r)), sleep(60000).then(() => 'timeout')]);
  check(code === 0, `the stop button ended the run (exit status ${code})`);
} catch (e) {
  check(false, 'exception: ' + (e.stack || e));
} finally {
  await browser.close();
  if (child.exitCode === null) child.kill('SIGTERM');
}
console.log(failures === 0 ? 'all browser checks passed; screenshots in ' + out : `${failures} browser check(s) failed`);
process.exit(failures === 0 ? 0 : 1);
