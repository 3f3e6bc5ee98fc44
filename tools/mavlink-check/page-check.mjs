// The monitor's live page in a real browser: `rgbdtam-monitor --http` runs, Debian's Chromium
// (headless, driven by playwright-core) loads its page, then `rgbdtam run` streams the committed
// clip. This script sits between them as a MAVLink router would: it forwards the runtime's
// datagrams to the monitor and plays the autopilot (node-mavlink HEARTBEATs to the runtime).
// It checks what the page rendered: a screenshot during the run and one at the end (written
// beside <out-prefix>), and the DOM's values against the run's own summary.
//   node page-check.mjs <bin dir> <board folder> <out-prefix>
import dgram from 'node:dgram';
import net from 'node:net';
import { spawn } from 'node:child_process';
import { join } from 'node:path';
import { MavLinkProtocolV2, minimal } from 'node-mavlink';
import { chromium } from 'playwright-core';

const [bin, board, out] = process.argv.slice(2);
const failures = [];
const check = (ok, what) => { if (!ok) failures.push(what); };
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

const freeTcpPort = () => new Promise((resolve) => {
  const server = net.createServer();
  server.listen(0, '127.0.0.1', () => { const { port } = server.address(); server.close(() => resolve(port)); });
});
const udp = async () => {
  const socket = dgram.createSocket('udp4');
  await new Promise((resolve) => socket.bind(0, '127.0.0.1', resolve));
  return socket;
};

// The monitor: UDP in, the page on HTTP.
const monitorUdp = await udp();
const monitorPort = monitorUdp.address().port;
monitorUdp.close();
const httpPort = await freeTcpPort();
const monitor = spawn(join(bin, 'rgbdtam-monitor'), ['--port', String(monitorPort), '--http',
  `127.0.0.1:${httpPort}`, '--quiet'], { stdio: ['ignore', 'pipe', 'inherit'] });
let monitorOut = '';
monitor.stdout.on('data', (d) => { monitorOut += d; });
for (let i = 0; i < 100 && !monitorOut.includes('live page'); ++i) await sleep(50);
check(monitorOut.includes(`live page: http://127.0.0.1:${httpPort}/`), 'the monitor did not say where its page is');

// The router and autopilot between the runtime and the monitor.
const router = await udp();
const autopilot = new MavLinkProtocolV2(1, 1);
let seq = 0;
let runtime = null;
const heartbeat = () => {
  if (!runtime) return;
  const hb = new minimal.Heartbeat();
  hb.type = minimal.MavType.QUADROTOR;
  hb.autopilot = minimal.MavAutopilot.PX4;
  hb.systemStatus = minimal.MavState.ACTIVE;
  hb.mavlinkVersion = 3;
  router.send(autopilot.serialize(hb, seq++ % 256), runtime.port, runtime.address);
};
router.on('message', (data, from) => {
  if (runtime === null) { runtime = from; heartbeat(); }
  router.send(data, monitorPort, '127.0.0.1');
});
const timer = setInterval(heartbeat, 500);

const browser = await chromium.launch({
  executablePath: '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
const page = await browser.newPage({ viewport: { width: 1100, height: 660 } });
const requests = [];
page.on('request', (r) => requests.push(r.url()));
await page.goto(`http://127.0.0.1:${httpPort}/`);
await page.waitForFunction(() => document.getElementById('connection').textContent === 'live');
const text = (id) => page.$eval(`#${id}`, (e) => e.textContent);
check(await text('state') === 'waiting', 'the page does not start as waiting');

const run = spawn(join(bin, 'rgbdtam'), ['run', '--board', board, '--board-set',
  `link.udp_remote=127.0.0.1:${router.address().port}`, '--quiet'], { stdio: ['ignore', 'pipe', 'inherit'] });
let runOut = '';
run.stdout.on('data', (d) => { runOut += d; });
const ended = new Promise((resolve) => run.on('exit', resolve));

// During the run: the trajectory grows and the state is live.
await page.waitForFunction(() => Number(document.getElementById('odometry').textContent) >= 12,
  null, { timeout: 20000 });
const during = { state: await text('state'), points: Number(await text('points')), rate: Number(await text('rate')) };
await page.screenshot({ path: `${out}-during.png` });
check(during.state === 'tracking', `state during the run: ${during.state}`);

const code = await ended;
check(code === 0, `rgbdtam run exited with ${code}`);
const frames = Number((runOut.match(/frames: (\d+) in/) || [])[1]);
const tracked = Number((runOut.match(/tracked (\d+), lost (\d+)/) || [])[1]);
await page.waitForFunction((n) => Number(document.getElementById('odometry').textContent) === n,
  frames, { timeout: 10000 }).catch(() => {});
await sleep(600);  // one more poll for the last texts
const dom = {};
for (const id of ['state', 'odometry', 'valid', 'lost', 'points', 'crc', 'gaps', 'resets', 'autopilot', 'heartbeats', 'quality', 'latency']) {
  dom[id] = await text(id);
}
const log = await page.$$eval('#log li', (items) => items.map((i) => i.dataset.text));
// The canvas shows a path: pixels in the trajectory's blue.
const blue = await page.$eval('#top-view', (c) => {
  const pixels = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let n = 0;
  for (let i = 0; i < pixels.length; i += 4) if (pixels[i + 2] > 150 && pixels[i] < 100) ++n;
  return n;
});
await page.screenshot({ path: `${out}-end.png` });
await browser.close();
clearInterval(timer);
router.close();
monitor.kill('SIGINT');
await new Promise((resolve) => monitor.on('exit', resolve));

check(frames > 0, 'no frame count in the run summary');
check(Number(dom.odometry) === frames, `page: ${dom.odometry} ODOMETRY for ${frames} frames`);
check(Number(dom.valid) === tracked, `page: ${dom.valid} tracked for ${tracked}`);
check(Number(dom.points) === frames, `page: ${dom.points} trajectory points for ${frames} frames`);
check(during.points < frames, 'the mid-run screenshot was not taken during the run');
check(dom.crc === '0' && dom.gaps === '0', `page: link errors crc ${dom.crc}, gaps ${dom.gaps}`);
check(/^present, system 1 component 1, MAV_AUTOPILOT 12$/.test(dom.autopilot), `page: autopilot "${dom.autopilot}"`);
check(log.some((t) => t.startsWith('autopilot: heard')), 'page: the STATUSTEXT log lacks the autopilot');
check(Number(dom.heartbeats) >= 1, 'page: no heartbeat');
// The firmware's latency, once a second: median <= p95 <= max, as run's summary has them.
const latency = dom.latency.split(' / ').map(Number);
check(latency.length === 3 && latency.every((v) => v > 0) && latency[0] <= latency[1] && latency[1] <= latency[2],
  `page: latency "${dom.latency}"`);
check(blue > 100, `page: the top view drew ${blue} trajectory pixels`);
const foreign = requests.filter((u) => !u.startsWith(`http://127.0.0.1:${httpPort}/`));
check(foreign.length === 0, `the page asked for ${foreign.join(', ')}`);

console.log(`monitor page in Chromium: during the run ${during.points} points, state ${during.state}, ` +
  `${during.rate} Hz; at the end ${dom.odometry} ODOMETRY (${dom.valid} tracked, ${dom.lost} lost) ` +
  `of ${frames} frames, ${dom.points} points, ${blue} path pixels, autopilot "${dom.autopilot}", ` +
  `latency ${dom.latency} ms, ${log.length} STATUSTEXT, ${requests.length} requests all to the monitor; screenshots ${out}-during.png, ${out}-end.png`);
if (failures.length > 0) {
  console.error(`page-check FAILED:\n  ${[...new Set(failures)].join('\n  ')}`);
  process.exit(1);
}
