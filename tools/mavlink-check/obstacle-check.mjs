// OBSTACLE_DISTANCE's geometry as node-mavlink decodes it: `rgbdtam run` on a synthetic
// sequence of a wall at a known distance and angle (rgbdtam-stress wall), each sector's distance
// against the wall's nearest point within the sector, computed here from the message's own
// angle_offset and increment_f.
//   node obstacle-check.mjs <rgbdtam binary> <board folder> <wall folder> <distance m> <yaw deg>
import dgram from 'node:dgram';
import { spawn } from 'node:child_process';
import path from 'node:path';
import { MavLinkPacketSplitter, MavLinkPacketParser, common } from 'node-mavlink';

const [binary, board, wall, distanceArg, yawArg] = process.argv.slice(2);
const distanceM = Number(distanceArg);
const yawDeg = Number(yawArg);
const failures = [];
const check = (ok, what) => { if (!ok) failures.push(what); };

const socket = dgram.createSocket('udp4');
await new Promise((resolve) => socket.bind(0, '127.0.0.1', resolve));
const splitter = new MavLinkPacketSplitter();
const obstacles = [];
splitter.pipe(new MavLinkPacketParser()).on('data', (p) => {
  if (p.header.msgid === common.ObstacleDistance.MSG_ID) {
    obstacles.push(p.protocol.data(p.payload, common.ObstacleDistance));
  }
});
socket.on('message', (data) => splitter.write(data));

const dir = path.resolve(wall);
const child = spawn(binary, ['run', '--board', board, '--quiet', '--set', 'loop.enabled=false',
  '--board-set', `link.udp_remote=127.0.0.1:${socket.address().port}`,
  '--board-set', `sensor.device=${dir}`, '--board-set', `sensor.config=${dir}/camera.conf`],
{ stdio: ['ignore', 'ignore', 'inherit'] });
const code = await new Promise((resolve) => child.on('exit', resolve));
await new Promise((resolve) => setTimeout(resolve, 300));  // the last datagrams
socket.close();
splitter.end();
await new Promise((resolve) => setTimeout(resolve, 100));

check(code === 0, `rgbdtam run exited with ${code}`);
check(obstacles.length > 0, 'no OBSTACLE_DISTANCE');
// The wall is vertical: along a bearing b (clockwise from forward, body frame) its horizontal
// distance is d / cos(b - yaw); a sector's nearest point is at the bearing closest to yaw.
const rad = Math.PI / 180;
let worst = 0;
let sum = 0;
let n = 0;
for (const o of obstacles) {
  check(o.frame === common.MavFrame.BODY_FRD, `frame ${o.frame}`);
  check(o.distances.filter((d) => d !== 65535).length >= 70, 'more than two sectors unseen');
  o.distances.forEach((d, i) => {
    if (d === 65535) return;  // an outermost sector the camera's samples miss
    const from = o.angleOffset + (i - 0.5) * o.incrementF;
    const to = from + o.incrementF;
    const nearest = Math.min(Math.max(yawDeg, from), to);
    const expectedCm = 100 * distanceM / Math.cos((nearest - yawDeg) * rad);
    check(d <= o.maxDistance, `sector ${i}: ${d} (no obstacle reported before a wall)`);
    const error = d - expectedCm;
    // Samples 4 px apart miss a sector's nearest point by up to the wall's slope across them.
    const slope = Math.tan(Math.abs(nearest - yawDeg) * rad);
    const allowed = 1 + expectedCm * slope * 4 / 525;
    check(error > -1 && error < allowed, `sector ${i}: ${d} cm, the wall is ${expectedCm.toFixed(1)} cm`);
    worst = Math.max(worst, Math.abs(error));
    sum += Math.abs(error);
    n += 1;
  });
}
console.log(`node-mavlink OBSTACLE_DISTANCE on a wall ${distanceM} m away at ${yawDeg} deg: ` +
  `${obstacles.length} messages, ${n} sectors, error mean ${(sum / n).toFixed(2)} cm, ` +
  `worst ${worst.toFixed(2)} cm`);
if (failures.length > 0) {
  console.error(`obstacle-check FAILED:\n  ${[...new Set(failures)].slice(0, 20).join('\n  ')}`);
  process.exit(1);
}
