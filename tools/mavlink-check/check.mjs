// Decodes the UDP stream of `rgbdtam run` on the committed clip with node-mavlink, a MAVLink
// implementation we did not write, acting as the autopilot: it sends HEARTBEAT and TIMESYNC
// back and checks what the runtime makes of them.
//   node check.mjs <rgbdtam binary> <board folder>
import dgram from 'node:dgram';
import { spawn } from 'node:child_process';
import { PassThrough } from 'node:stream';
import {
  MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV2, minimal, common,
} from 'node-mavlink';

const [binary, board] = process.argv.slice(2);
const failures = [];
const check = (ok, what) => { if (!ok) failures.push(what); };

const socket = dgram.createSocket('udp4');
await new Promise((resolve) => socket.bind(0, '127.0.0.1', resolve));
const splitter = new MavLinkPacketSplitter();
const wire = new PassThrough();
const packets = [];
wire.pipe(splitter).pipe(new MavLinkPacketParser()).on('data', (p) => packets.push(p));

// The autopilot's side: PX4's system 1, component 1.
const autopilot = new MavLinkProtocolV2(1, 1);
let seq = 0;
let runtime = null;  // where the runtime sends from, learnt from its first datagram
const say = (msg) => { if (runtime) socket.send(autopilot.serialize(msg, seq++ % 256), runtime.port, runtime.address); };
const heartbeat = () => {
  const hb = new minimal.Heartbeat();
  hb.type = minimal.MavType.QUADROTOR;
  hb.autopilot = minimal.MavAutopilot.PX4;
  hb.systemStatus = minimal.MavState.ACTIVE;
  hb.mavlinkVersion = 3;
  say(hb);
};
// Our TIMESYNC requests, with each heartbeat, as autopilots ask again and again: the runtime
// answers once its first frame has given it a clock to answer in.
const ourTs1 = new Set();
const request = () => {
  const r = new common.TimeSync();
  r.tc1 = 0n;
  r.ts1 = 123456789n + BigInt(ourTs1.size);
  ourTs1.add(r.ts1);
  say(r);
};
socket.on('message', (data, from) => {
  if (runtime === null) {
    runtime = from;
    heartbeat();
    request();
  }
  wire.write(data);
});
const timer = setInterval(() => { heartbeat(); request(); }, 500);

const child = spawn(binary, ['run', '--board', board, '--board-set',
  `link.udp_remote=127.0.0.1:${socket.address().port}`, '--quiet'], { stdio: ['ignore', 'pipe', 'inherit'] });
let stdout = '';
child.stdout.on('data', (d) => { stdout += d; });
const code = await new Promise((resolve) => child.on('exit', resolve));
await new Promise((resolve) => setTimeout(resolve, 300));  // the last datagrams
clearInterval(timer);
socket.close();
wire.end();
await new Promise((resolve) => setTimeout(resolve, 100));

check(code === 0, `rgbdtam run exited with ${code}`);
const tracked = Number((stdout.match(/tracked (\d+), lost (\d+)/) || [])[1]);
const frames = Number((stdout.match(/frames: (\d+) in/) || [])[1]);
const decode = (p, clazz) => p.protocol.data(p.payload, clazz);
const byId = (id) => packets.filter((p) => p.header.msgid === id);
const odometry = byId(common.Odometry.MSG_ID).map((p) => decode(p, common.Odometry));
const heartbeats = byId(minimal.Heartbeat.MSG_ID).map((p) => ({ t: p.timestamp, hb: decode(p, minimal.Heartbeat) }));
const answers = byId(common.TimeSync.MSG_ID).map((p) => decode(p, common.TimeSync));
const obstacles = byId(common.ObstacleDistance.MSG_ID).map((p) => decode(p, common.ObstacleDistance));
const values = byId(common.NamedValueFloat.MSG_ID).map((p) => decode(p, common.NamedValueFloat));

check(splitter.invalidPackages === 0, `${splitter.invalidPackages} frames failed their CRC`);
check(splitter.unknownPackagesCount === 0, `${splitter.unknownPackagesCount} frames of unknown messages`);
check(odometry.length === frames, `${odometry.length} ODOMETRY for ${frames} frames`);
const valid = odometry.filter((o) => o.quality >= 0);
check(valid.length === tracked && tracked > 0, `${valid.length} valid ODOMETRY for ${tracked} tracked frames`);
for (const o of valid) {
  const norm = Math.hypot(...o.q);
  check(Math.abs(norm - 1) < 1e-5, `quaternion norm ${norm}`);
  check(o.frameId === common.MavFrame.LOCAL_FRD && o.childFrameId === common.MavFrame.BODY_FRD,
    `frames ${o.frameId}/${o.childFrameId}`);
  check(o.estimatorType === common.MavEstimatorType.VISION, `estimator type ${o.estimatorType}`);
  // MAVLink's "unknown" is NaN in the first element: only the first frame, which defines the
  // origin and has no measurement, may say so.
  if (Number.isNaN(o.poseCovariance[0])) continue;
  check(o.poseCovariance.every(Number.isFinite), 'a non-finite pose covariance');
  check([o.poseCovariance[0], o.poseCovariance[6], o.poseCovariance[11]].every((v) => v > 0),
    'a position variance that is not positive');
  check(o.quality >= 1 && o.quality <= 100, `quality ${o.quality}`);
}
const unknown = valid.filter((o) => Number.isNaN(o.poseCovariance[0])).length;
check(unknown <= 1, `${unknown} valid poses without a covariance`);
const stamps = odometry.map((o) => Number(o.timeUsec));
check(stamps.every((t, i) => i === 0 || t > stamps[i - 1]), 'time_usec not increasing');
// HEARTBEAT at about 1 Hz, from the runtime's system and component.
const expected = Math.ceil((frames / 30));
check(Math.abs(heartbeats.length - expected) <= 1, `${heartbeats.length} HEARTBEAT in a ${frames / 30} s run`);
check(heartbeats.every(({ hb }) => hb.type === minimal.MavType.ONBOARD_CONTROLLER), 'HEARTBEAT type');
// The runtime heard us: it answered our TIMESYNC and reported the autopilot.
const answer = answers.find((a) => a.tc1 !== 0n && ourTs1.has(a.ts1));
check(answer !== undefined, 'no answer to our TIMESYNC request');
if (answer) check(answer.targetSystem === 1 && answer.targetComponent === 1, 'TIMESYNC answer targets');
check(/autopilot: system 1 component 1, MAV_AUTOPILOT 12 \(PX4\)/.test(stdout), 'the run did not report the autopilot');
// OBSTACLE_DISTANCE at the board's 10 Hz (every third frame of the clip), in the body frame,
// whether or not tracking is valid; each sector a distance within the range, "none" (max + 1)
// or "unknown" (UINT16_MAX).
check(Math.abs(obstacles.length - frames / 3) <= 1, `${obstacles.length} OBSTACLE_DISTANCE for ${frames} frames`);
let known = 0;
for (const o of obstacles) {
  check(o.distances.length === 72, `${o.distances.length} sectors`);
  check(o.frame === common.MavFrame.BODY_FRD, `OBSTACLE_DISTANCE frame ${o.frame}`);
  // The clip's camera looks forward (the board's link.T_b_c): 72 sectors over its 63.5 degrees
  // (fx 517.3 px over 640), centred on forward, sector 0's centre as the offset.
  const span = o.incrementF * 72;
  check(Math.abs(span - 63.48) < 0.05, `increment_f ${o.incrementF}: a span of ${span} degrees`);
  check(Math.abs(o.angleOffset - (-span / 2 + o.incrementF / 2)) < 0.01, `angle_offset ${o.angleOffset}`);
  check(o.minDistance === 30 && o.maxDistance > o.minDistance, `range ${o.minDistance}-${o.maxDistance} cm`);
  for (const d of o.distances) {
    check(d === 65535 || d === o.maxDistance + 1 || (d >= o.minDistance && d <= o.maxDistance), `sector distance ${d}`);
    if (d !== 65535) known += 1;
  }
}
const obstacleStamps = obstacles.map((o) => Number(o.timeUsec));
check(obstacleStamps.every((t, i) => i === 0 || t > obstacleStamps[i - 1]), 'OBSTACLE_DISTANCE time_usec not increasing');
check(known > obstacles.length * 72 / 2, `only ${known} of ${obstacles.length * 72} sectors known`);
// The latency so far, once a second, as NAMED_VALUE_FLOAT: median <= p95 <= max, all positive.
const latest = (name) => values.filter((v) => v.name.replace(/\0+$/, '') === name).map((v) => v.value).pop();
const latency = ['lat_med_ms', 'lat_p95_ms', 'lat_max_ms'].map(latest);
check(latency.every((v) => v > 0) && latency[0] <= latency[1] && latency[1] <= latency[2],
  `latency NAMED_VALUE_FLOAT ${latency.join(', ')}`);

console.log(`node-mavlink ${splitter.validPackages} frames, all CRC-valid: ${odometry.length} ODOMETRY ` +
  `(${valid.length} valid) for ${frames} frames, ${heartbeats.length} HEARTBEAT, ` +
  `${answers.length} TIMESYNC (our request answered: ${answer !== undefined}), ` +
  `${unknown} pose(s) with an unknown covariance, ${obstacles.length} OBSTACLE_DISTANCE ` +
  `(${known} of ${obstacles.length * 72} sectors known), latency ${latency.map((v) => v && v.toFixed(2)).join(' / ')} ms ` +
  `(${values.length / 3} NAMED_VALUE_FLOAT sets)`);
if (failures.length > 0) {
  console.error(`mavlink-check FAILED:\n  ${[...new Set(failures)].join('\n  ')}`);
  process.exit(1);
}
