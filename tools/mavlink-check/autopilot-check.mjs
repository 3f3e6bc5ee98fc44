// A scripted autopilot, written with node-mavlink (a MAVLink implementation we did not write),
// against `rgbdtam run` on a TUM sequence: HEARTBEAT, TIMESYNC answered from a boot clock of its
// own, and the ground truth's attitude as ATTITUDE_QUATERNION at 100 Hz (a body on the board's
// link.T_b_c, in a level frame of its own), with noise, late by a latency, or stamped wrong by a
// skew. It checks that the runtime levels ODOMETRY's frame by that gravity and reports what the
// prior did.
//   node autopilot-check.mjs <rgbdtam binary> <board folder> <sequence folder>
//        [--noise-deg 0.2] [--latency-ms 5] [--skew-ms 0] [--max-down-deg 3]
// The down direction's worst error is the level's own (at most a degree or so) plus the
// tracker's rotation drift since, which grows with the sequence.
import dgram from 'node:dgram';
import { readFileSync } from 'node:fs';
import { spawn } from 'node:child_process';
import { PassThrough } from 'node:stream';
import {
  MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV2, minimal, common,
} from 'node-mavlink';

const [binary, board, sequence, ...rest] = process.argv.slice(2);
const option = (name, fallback) => {
  const i = rest.indexOf(name);
  return i >= 0 ? Number(rest[i + 1]) : fallback;
};
const noiseDeg = option('--noise-deg', 0.2);
const latencyMs = option('--latency-ms', 5);
const skewMs = option('--skew-ms', 0);
const maxDownDeg = option('--max-down-deg', 3);
const failures = [];
const check = (ok, what) => { if (!ok) failures.push(what); };

// Quaternions as [w, x, y, z].
const mul = (a, b) => [
  a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
  a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
  a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
  a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
];
const conj = (q) => [q[0], -q[1], -q[2], -q[3]];
const normalised = (q) => { const n = Math.hypot(...q); return q.map((v) => v / n); };
const rotate = (q, v) => mul(mul(q, [0, ...v]), conj(q)).slice(1);
const fromRotationVector = (r) => {
  const angle = Math.hypot(...r);
  if (angle < 1e-12) return [1, 0, 0, 0];
  const s = Math.sin(angle / 2) / angle;
  return [Math.cos(angle / 2), r[0] * s, r[1] * s, r[2] * s];
};
const gaussian = () => Math.sqrt(-2 * Math.log(1 - Math.random())) * Math.cos(2 * Math.PI * Math.random());

// The ground truth (TUM: t tx ty tz qx qy qz qw), the camera in the motion capture's frame.
const truth = readFileSync(`${sequence}/groundtruth.txt`, 'utf8').split('\n')
  .filter((l) => l && !l.startsWith('#')).map((l) => l.trim().split(/\s+/).map(Number))
  .map(([t, , , , qx, qy, qz, qw]) => ({ t, q: normalised([qw, qx, qy, qz]) }));
const cameraAt = (t) => {
  let hi = truth.findIndex((p) => p.t >= t);
  if (hi <= 0) return null;
  const a = truth[hi - 1], b = truth[hi];
  if (b.t - a.t > 0.05) return null;
  const f = (t - a.t) / (b.t - a.t);
  const sign = a.q.reduce((s, v, i) => s + v * b.q[i], 0) < 0 ? -1 : 1;
  return normalised(a.q.map((v, i) => (1 - f) * v + f * sign * b.q[i]));  // nlerp: 10 ms apart
};
// The board's mounting, and the autopilot's level frame: a tilt and heading of its own.
const boardText = readFileSync(`${board}/board.conf`, 'utf8');
const mounting = (boardText.match(/^link\.T_b_c\s*=\s*(.*)$/m) || [null, '1 0 0 0 0 0 0'])[1]
  .trim().split(/\s+/).map(Number);
const qBC = normalised(mounting.slice(0, 4));
const qNM = fromRotationVector([0.3, -0.2, 0.7]);
const bodyAt = (sensorS) => {
  const qMC = cameraAt(sensorS);
  return qMC ? mul(mul(qNM, qMC), conj(qBC)) : null;
};

const socket = dgram.createSocket('udp4');
await new Promise((resolve) => socket.bind(0, '127.0.0.1', resolve));
const splitter = new MavLinkPacketSplitter();
const wire = new PassThrough();
const packets = [];
wire.pipe(splitter).pipe(new MavLinkPacketParser()).on('data', (p) => packets.push(p));
const autopilot = new MavLinkProtocolV2(1, 1);
let seq = 0;
let runtime = null;
const say = (msg) => { if (runtime) socket.send(autopilot.serialize(msg, seq++ % 256), runtime.port, runtime.address); };
const started = process.hrtime.bigint();
const bootNs = () => process.hrtime.bigint() - started + 10_000_000_000n;  // booted 10 s ago
const wallS = () => Number(process.hrtime.bigint()) * 1e-9;
// The sensor's clock from ODOMETRY: time_usec minus the wall time it arrived, at its largest
// (the fastest delivery), is the sensor's clock minus ours.
let sensorMinusWallS = null;
let timesyncAnswered = 0;
const heartbeat = () => {
  const hb = new minimal.Heartbeat();
  hb.type = minimal.MavType.QUADROTOR;
  hb.autopilot = minimal.MavAutopilot.ARDUPILOTMEGA;
  hb.systemStatus = minimal.MavState.ACTIVE;
  hb.mavlinkVersion = 3;
  say(hb);
};
const parser = new MavLinkPacketParser();
splitter.pipe(parser);
parser.on('data', (p) => {
  if (p.header.msgid === common.TimeSync.MSG_ID) {
    const t = p.protocol.data(p.payload, common.TimeSync);
    if (t.tc1 !== 0n) return;
    const answer = new common.TimeSync();
    answer.tc1 = bootNs();
    answer.ts1 = t.ts1;
    answer.targetSystem = p.header.sysid;
    answer.targetComponent = p.header.compid;
    say(answer);
    timesyncAnswered += 1;
  } else if (p.header.msgid === common.Odometry.MSG_ID) {
    const o = p.protocol.data(p.payload, common.Odometry);
    const offset = Number(o.timeUsec) * 1e-6 - wallS();
    if (sensorMinusWallS === null || offset > sensorMinusWallS) sensorMinusWallS = offset;
  }
});
socket.on('message', (data, from) => {
  if (runtime === null) { runtime = from; heartbeat(); }
  wire.write(data);
});
const beat = setInterval(heartbeat, 500);
// 100 Hz: the body's attitude latency_ms ago, stamped in the boot clock (plus the skew).
let attitudesSent = 0;
const stream = setInterval(() => {
  if (sensorMinusWallS === null) return;
  const sensorS = wallS() + sensorMinusWallS - latencyMs * 1e-3;
  const q = bodyAt(sensorS);
  const qLater = bodyAt(sensorS + 0.001);
  if (!q || !qLater) return;
  const d = mul(conj(q), qLater);
  const rate = [d[1], d[2], d[3]].map((v) => 2 * v / 0.001 * Math.sign(d[0] || 1));
  const noise = fromRotationVector([0, 1, 2].map(() => gaussian() * noiseDeg * Math.PI / 180));
  const qSent = normalised(mul(q, noise));
  const m = new common.AttitudeQuaternion();
  const bootAtSample = bootNs() - BigInt(Math.round(latencyMs * 1e6)) + BigInt(Math.round(skewMs * 1e6));
  m.timeBootMs = Number(bootAtSample / 1_000_000n);
  [m.q1, m.q2, m.q3, m.q4] = qSent;
  [m.rollspeed, m.pitchspeed, m.yawspeed] = rate;
  m.reprOffsetQ = [0, 0, 0, 0];
  say(m);
  attitudesSent += 1;
}, 10);

const child = spawn(binary, ['run', '--board', board, '--board-set',
  `link.udp_remote=127.0.0.1:${socket.address().port}`, '--board-set', `sensor.device=${sequence}`,
  '--quiet'], { stdio: ['ignore', 'pipe', 'inherit'] });
let stdout = '';
child.stdout.on('data', (d) => { stdout += d; });
const code = await new Promise((resolve) => child.on('exit', resolve));
await new Promise((resolve) => setTimeout(resolve, 300));
clearInterval(beat);
clearInterval(stream);
socket.close();
wire.end();
await new Promise((resolve) => setTimeout(resolve, 100));

check(code === 0, `rgbdtam run exited with ${code}`);
check(splitter.invalidPackages === 0, `${splitter.invalidPackages} frames failed their CRC`);
const odometry = packets.filter((p) => p.header.msgid === common.Odometry.MSG_ID)
  .map((p) => p.protocol.data(p.payload, common.Odometry));
const valid = odometry.filter((o) => o.quality >= 0);
// After levelling (the last reset_counter), the body's down in ODOMETRY's frame is the
// autopilot's down.
const levelled = valid.length > 0 ? valid[valid.length - 1].resetCounter : -1;
let checked = 0, worst = 0;
for (const o of valid) {
  if (o.resetCounter !== levelled) continue;
  const q = bodyAt(Number(o.timeUsec) * 1e-6);
  if (!q) continue;
  const sent = rotate(conj(normalised([...o.q])), [0, 0, 1]);
  const real = rotate(conj(q), [0, 0, 1]);
  const dot = Math.min(1, sent.reduce((s, v, i) => s + v * real[i], 0));
  worst = Math.max(worst, Math.acos(dot) * 180 / Math.PI);
  checked += 1;
}
const summary = (stdout.match(/^attitude: .*$/m) || ['attitude: (no summary line)'])[0];
check(/frame levelled by gravity/.test(summary), 'ODOMETRY was not levelled');
check(checked >= 10, `only ${checked} levelled poses to check`);
check(worst <= maxDownDeg, `down in ODOMETRY's frame ${worst.toFixed(2)} deg from the autopilot's`);
const used = Number((summary.match(/(\d+) stood/) || [])[1]);
const refused = Number((summary.match(/(\d+) refused by the image/) || [])[1]);
console.log(`node-mavlink autopilot on ${sequence.split('/').pop()} (noise ${noiseDeg} deg, ` +
  `latency ${latencyMs} ms, skew ${skewMs} ms): ${attitudesSent} ATTITUDE_QUATERNION sent, ` +
  `${timesyncAnswered} TIMESYNC answered; ${valid.length} valid ODOMETRY, ${checked} levelled, ` +
  `their down within ${worst.toFixed(2)} deg of the autopilot's; prior stood ${used}, refused ${refused}`);
console.log(`  ${summary}`);
console.log(`  ${(stdout.match(/^timesync: .*$/m) || ['timesync: (no summary line)'])[0]}`);
if (failures.length > 0) {
  console.error(`autopilot-check FAILED:\n  ${[...new Set(failures)].join('\n  ')}`);
  process.exit(1);
}
