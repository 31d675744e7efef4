// Independent check of `faultline bag corrupt` (issue #18 item 3a). Usage:
//   node bag_corrupt_check.mjs FAULTLINE_BINARY WORK_DIR
// 1. Writes a rosbag2 directory of input with the npm writers only (@mcap/core McapWriter, ros2msg definitions
//    parsed by @foxglove/rosmsg, CDR from @foxglove/rosmsg2-serialization, metadata.yaml as text): two
//    CompressedImage topics with small JPEGs, an Image topic in bgr8 and one in rgb8 (padded rows), /tf and a
//    std_msgs/String topic. The JPEG payloads are made from pictures drawn here by `faultline corrupt --severity 0`
//    (no corruption, only the JPEG encoding: Node has no JPEG encoder of its own).
// 2. Runs `faultline bag corrupt` on it (numpy mode, 2 threads).
// 3. Reads both bags in file order with McapStreamReader and checks: pass-through topics byte-identical (schema,
//    channel metadata, message bytes, sequence, log and publish times), the order of all messages kept, and every
//    faulted frame equal to `faultline corrupt` of the same input frame with the type, severity and seed its
//    DiagnosticArray event names, decoding the output with the output bag's own embedded schemas.
// Exits non-zero with a message naming the topic and frame on the first difference.
import { McapStreamReader, McapWriter } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parse } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import { execFileSync } from "node:child_process";
import { mkdirSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { join } from "node:path";

const [faultline, work] = process.argv.slice(2);
if (!faultline || !work) {
  console.error("usage: node bag_corrupt_check.mjs FAULTLINE_BINARY WORK_DIR");
  process.exit(2);
}

const SEP = "=".repeat(80);
const TIME = "int32 sec\nuint32 nanosec\n";
const HEADER = "builtin_interfaces/Time stamp\nstring frame_id\n";
const deps = (...pairs) => pairs.map(([name, text]) => `${SEP}\nMSG: ${name}\n${text}`).join("");
const DEFS = {
  "sensor_msgs/msg/CompressedImage":
    "std_msgs/Header header\nstring format\nuint8[] data\n" +
    deps(["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME]),
  "sensor_msgs/msg/Image":
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\n" +
    "uint8[] data\n" + deps(["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME]),
  "std_msgs/msg/String": "string data\n",
  "tf2_msgs/msg/TFMessage":
    "geometry_msgs/TransformStamped[] transforms\n" +
    deps(
      ["geometry_msgs/TransformStamped", "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n"],
      ["std_msgs/Header", HEADER],
      ["builtin_interfaces/Time", TIME],
      ["geometry_msgs/Transform", "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n"],
      ["geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"],
      ["geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"],
    ),
};
const QOS_SENSOR =
  "- history: 1\n  depth: 5\n  reliability: 2\n  durability: 2\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n" +
  "  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n  liveliness_lease_duration:\n" +
  "    sec: 9223372036\n    nsec: 854775807\n  avoid_ros_namespace_conventions: false";
const QOS_DEFAULT = QOS_SENSOR.replace("depth: 5", "depth: 10").replace("reliability: 2", "reliability: 1");

const TOPICS = [
  { topic: "/tf", type: "tf2_msgs/msg/TFMessage", qos: QOS_DEFAULT },
  { topic: "/cam_front/image_compressed", type: "sensor_msgs/msg/CompressedImage", qos: QOS_SENSOR, fault: "fog:mid" },
  { topic: "/cam_back/image_compressed", type: "sensor_msgs/msg/CompressedImage", qos: QOS_SENSOR, fault: "snow:easy" },
  { topic: "/cam_left/image_raw", type: "sensor_msgs/msg/Image", qos: QOS_SENSOR, fault: "brightness:mid", encoding: "bgr8" },
  { topic: "/cam_right/image_raw", type: "sensor_msgs/msg/Image", qos: QOS_SENSOR, fault: "dark:hard", encoding: "rgb8" },
  { topic: "/chatter", type: "std_msgs/msg/String", qos: QOS_DEFAULT },
];
const FRAMES = 4;
const W = 40, H = 24;
const T0 = 1_700_000_000_000_000_000n;
const PERIOD = 100_000_000n;

function fail(why) {
  console.error(`bag corrupt check: ${why}`);
  process.exit(1);
}

// RGB picture of frame i, one per topic index k.
function picture(i, k) {
  const rgb = new Uint8Array(W * H * 3);
  for (let y = 0; y < H; y++) {
    for (let x = 0; x < W; x++) {
      const o = (y * W + x) * 3;
      rgb[o] = (x * 6 + i * 40 + k * 17) % 256;
      rgb[o + 1] = (y * 9 + x * 2 + k * 31) % 256;
      rgb[o + 2] = (x * y + i * 23) % 256;
    }
  }
  return rgb;
}

const ppm = (w, h, rgb) => Buffer.concat([Buffer.from(`P6\n${w} ${h}\n255\n`), Buffer.from(rgb)]);
function readPpm(path) {
  const b = readFileSync(path);
  const tokens = [];
  let i = 0;
  while (tokens.length < 4) {
    while (/\s/.test(String.fromCharCode(b[i]))) i++;
    if (b[i] === 0x23) { while (b[i] !== 0x0a) i++; continue; }  // comment
    let t = "";
    while (!/\s/.test(String.fromCharCode(b[i]))) t += String.fromCharCode(b[i++]);
    tokens.push(t);
  }
  i++;  // one whitespace byte after maxval
  const [magic, w, h] = [tokens[0], Number(tokens[1]), Number(tokens[2])];
  if (magic !== "P6" || tokens[3] !== "255") fail(`${path}: not an 8-bit P6 PPM`);
  return { w, h, rgb: b.subarray(i, i + w * h * 3) };
}

function run(args) {
  try {
    return execFileSync(faultline, args, { encoding: "utf8", stdio: ["ignore", "pipe", "pipe"] });
  } catch (e) {
    fail(`faultline ${args.join(" ")} exited ${e.status}: ${e.stderr}`);
  }
}

class MemoryWritable {
  constructor() { this.chunks = []; this.size = 0n; }
  position() { return this.size; }
  async write(buffer) { this.chunks.push(Buffer.from(buffer)); this.size += BigInt(buffer.byteLength); }
  bytes() { return Buffer.concat(this.chunks); }
}

async function writeInput(dir) {
  const jpegDir = join(work, "input_frames");
  mkdirSync(jpegDir, { recursive: true });
  const out = new MemoryWritable();
  const writer = new McapWriter({ writable: out, useStatistics: true, useChunks: true, chunkSize: 64 * 1024 });
  await writer.start({ profile: "ros2", library: "npm bag_corrupt_check" });
  const ids = new Map();
  const writers = new Map();
  for (const t of TOPICS) {
    const schemaId = await writer.registerSchema({ name: t.type, encoding: "ros2msg", data: Buffer.from(DEFS[t.type]) });
    const channelId = await writer.registerChannel({
      topic: t.topic, messageEncoding: "cdr", schemaId, metadata: new Map([["offered_qos_profiles", t.qos]]),
    });
    ids.set(t.topic, channelId);
    if (!writers.has(t.type)) writers.set(t.type, new MessageWriter(parse(DEFS[t.type], { ros2: true })));
  }
  const counts = new Map(TOPICS.map((t) => [t.topic, 0]));
  let total = 0;
  const add = async (topic, logTime, publishTime, msg, type) => {
    const seq = counts.get(topic) + 1;
    counts.set(topic, seq);
    total++;
    await writer.addMessage({ channelId: ids.get(topic), sequence: seq, logTime, publishTime,
                              data: writers.get(type).writeMessage(msg) });
  };
  for (let i = 0; i < FRAMES; i++) {
    const t = T0 + BigInt(i) * PERIOD;
    const stamp = { sec: Number(t / 1_000_000_000n), nanosec: Number(t % 1_000_000_000n) };
    await add("/tf", t, t - 1000n, { transforms: [{ header: { stamp, frame_id: "map" }, child_frame_id: "base_link",
      transform: { translation: { x: i, y: 0, z: 0 }, rotation: { x: 0, y: 0, z: 0, w: 1 } } }] }, "tf2_msgs/msg/TFMessage");
    for (const [k, tp] of TOPICS.entries()) {
      if (!tp.fault) continue;
      const rgb = picture(i, k);
      const header = { stamp, frame_id: tp.topic.split("/")[1] };
      const logTime = t + BigInt(k);
      if (tp.type === "sensor_msgs/msg/CompressedImage") {
        const src = join(jpegDir, `${k}_${i}.ppm`), jpg = join(jpegDir, `${k}_${i}.jpg`);
        writeFileSync(src, ppm(W, H, rgb));
        run(["corrupt", "--type", "fog", "--severity", "0", "--in", src, "--out", jpg]);
        await add(tp.topic, logTime, logTime + 7n, { header, format: "jpeg", data: readFileSync(jpg) }, tp.type);
      } else {
        const step = W * 3 + 2;  // padded rows
        const data = new Uint8Array(step * H).fill(0xa5);
        for (let y = 0; y < H; y++) {
          for (let x = 0; x < W; x++) {
            const s = (y * W + x) * 3, d = y * step + x * 3;
            const bgr = tp.encoding === "bgr8";
            data[d] = rgb[s + (bgr ? 2 : 0)];
            data[d + 1] = rgb[s + 1];
            data[d + 2] = rgb[s + (bgr ? 0 : 2)];
          }
        }
        await add(tp.topic, logTime, logTime + 7n, { header, height: H, width: W, encoding: tp.encoding,
                                                     is_bigendian: 0, step, data }, tp.type);
      }
    }
    await add("/chatter", i === 2 ? t - 30_000_000n : t + 9n, t + 9n, { data: `hello ${i}` }, "std_msgs/msg/String");
  }
  await writer.end();
  mkdirSync(dir, { recursive: true });
  const name = dir.split("/").pop();
  writeFileSync(join(dir, `${name}_0.mcap`), out.bytes());
  const end = T0 + BigInt(FRAMES - 1) * PERIOD + 9n;
  const yaml = [
    "rosbag2_bagfile_information:",
    "  version: 5",
    "  storage_identifier: mcap",
    `  duration:\n    nanoseconds: ${end - T0 + 1000n}`,
    `  starting_time:\n    nanoseconds_since_epoch: ${T0 - 1000n}`,
    `  message_count: ${total}`,
    "  topics_with_message_count:",
    ...TOPICS.flatMap((t) => [
      "    - topic_metadata:",
      `        name: ${t.topic}`,
      `        type: ${t.type}`,
      "        serialization_format: cdr",
      `        offered_qos_profiles: ${JSON.stringify(t.qos)}`,
      `      message_count: ${counts.get(t.topic)}`,
    ]),
    '  compression_format: ""',
    '  compression_mode: ""',
    "  relative_file_paths:",
    `    - ${name}_0.mcap`,
    "  files:",
    `    - path: ${name}_0.mcap`,
    `      starting_time:\n        nanoseconds_since_epoch: ${T0 - 1000n}`,
    `      duration:\n        nanoseconds: ${end - T0 + 1000n}`,
    `      message_count: ${total}`,
    "",
  ].join("\n");
  writeFileSync(join(dir, "metadata.yaml"), yaml);
  return total;
}

// Schemas, channels and messages in file order.
async function readBag(file) {
  const reader = new McapStreamReader({ decompressHandlers: await loadDecompressHandlers(), validateCrcs: true });
  reader.append(readFileSync(file));
  const bag = { schemas: new Map(), channels: new Map(), messages: [], profile: undefined };
  for (let r; (r = reader.nextRecord()); ) {
    if (r.type === "Header") bag.profile = r.profile;
    if (r.type === "Schema") bag.schemas.set(r.id, r);
    if (r.type === "Channel") bag.channels.set(r.id, r);
    if (r.type === "Message") {
      const c = bag.channels.get(r.channelId);
      bag.messages.push({ topic: c.topic, sequence: r.sequence, logTime: r.logTime, publishTime: r.publishTime,
                          data: Buffer.from(r.data) });
    }
  }
  if (!reader.done()) fail(`${file}: stream ends before the footer`);
  bag.byTopic = (topic) => bag.messages.filter((m) => m.topic === topic);
  bag.channel = (topic) => [...bag.channels.values()].find((c) => c.topic === topic);
  bag.schema = (topic) => bag.schemas.get(bag.channel(topic).schemaId);
  bag.reader = (topic) => {
    const s = bag.schema(topic);
    if (s.encoding !== "ros2msg") fail(`${topic}: schema encoding ${s.encoding}`);
    return new MessageReader(parse(new TextDecoder().decode(s.data), { ros2: true }));
  };
  return bag;
}

const same = (a, b) => Buffer.compare(Buffer.from(a), Buffer.from(b)) === 0;

async function main() {
  rmSync(work, { recursive: true, force: true });
  mkdirSync(work, { recursive: true });
  const inDir = join(work, "in_bag"), outDir = join(work, "out_bag");
  const total = await writeInput(inDir);
  const args = ["bag", "corrupt", "--in", inDir, "--out", outDir, "--rng", "numpy", "--seed", "11", "--threads", "2",
                "--quiet"];
  for (const t of TOPICS) if (t.fault) args.push("--fault", `${t.topic}=${t.fault}`);
  run(args);

  const a = await readBag(join(inDir, "in_bag_0.mcap"));
  const b = await readBag(join(outDir, "out_bag_0.mcap"));
  if (b.profile !== "ros2") fail(`output profile '${b.profile}'`);
  const faulted = new Set(TOPICS.filter((t) => t.fault).map((t) => t.topic));

  // Pass-through topics: schema, channel metadata, messages with sequence and times, byte for byte.
  for (const t of TOPICS) {
    const [sa, sb] = [a.schema(t.topic), b.schema(t.topic)];
    if (sa.name !== sb.name || sa.encoding !== sb.encoding || !same(sa.data, sb.data)) fail(`${t.topic}: schema differs`);
    const [ca, cb] = [a.channel(t.topic), b.channel(t.topic)];
    if (ca.messageEncoding !== cb.messageEncoding) fail(`${t.topic}: message encoding differs`);
    if (JSON.stringify([...ca.metadata]) !== JSON.stringify([...cb.metadata])) fail(`${t.topic}: channel metadata differs`);
    if (faulted.has(t.topic)) continue;
    const [ma, mb] = [a.byTopic(t.topic), b.byTopic(t.topic)];
    if (ma.length !== FRAMES || mb.length !== FRAMES) fail(`${t.topic}: ${ma.length} in, ${mb.length} out`);
    ma.forEach((m, i) => {
      const o = mb[i];
      if (m.sequence !== o.sequence || m.logTime !== o.logTime || m.publishTime !== o.publishTime || !same(m.data, o.data)) {
        fail(`${t.topic} message ${i}: not byte-identical (sequence, times or data)`);
      }
    });
  }
  const order = (bag) => bag.messages.filter((m) => m.topic !== "/faultline/faults").map((m) => m.topic).join(" ");
  if (order(a) !== order(b)) fail("message order differs");
  if (a.messages.length !== total) fail(`input has ${a.messages.length} messages, wrote ${total}`);

  // Fault events from the output's own DiagnosticArray schema; each faulted frame against `faultline corrupt`.
  if (b.schema("/faultline/faults").name !== "diagnostic_msgs/msg/DiagnosticArray") fail("faults topic type");
  const events = b.byTopic("/faultline/faults").map((m) => b.reader("/faultline/faults").readMessage(m.data));
  if (events.length !== FRAMES * faulted.size) fail(`${events.length} fault events, expected ${FRAMES * faulted.size}`);
  const seen = new Map();
  let compared = 0;
  for (const ev of events) {
    const st = ev.status[0];
    const v = Object.fromEntries(st.values.map((kv) => [kv.key, kv.value]));
    const topic = v.topic;
    const i = seen.get(topic) ?? 0;
    seen.set(topic, i + 1);
    const tp = TOPICS.find((t) => t.topic === topic);
    if (!tp || !tp.fault) fail(`fault event names topic ${topic}`);
    const f = tp.fault.split(":")[0];  // the fault's values are "<name>.severity", "<name>.seed", ...
    if (v.action !== "corrupt" || v[`${f}.rng`] !== "numpy" || v[`${f}.seed`] === undefined) {
      fail(`${topic} frame ${i}: event ${JSON.stringify(v)}`);
    }
    if (st.name !== `faultline${topic}` || st.level !== 1 || v.source_seq !== String(i + 1)) {
      fail(`${topic} frame ${i}: event name ${st.name}, level ${st.level}, source_seq ${v.source_seq}`);
    }
    const src = a.reader(topic).readMessage(a.byTopic(topic)[i].data);
    const outMsg = b.byTopic(topic)[i];
    const dst = b.reader(topic).readMessage(outMsg.data);
    if (dst.header.stamp.sec !== src.header.stamp.sec || dst.header.stamp.nanosec !== src.header.stamp.nanosec ||
        dst.header.frame_id !== src.header.frame_id) fail(`${topic} frame ${i}: header changed`);
    if (outMsg.logTime !== a.byTopic(topic)[i].logTime) fail(`${topic} frame ${i}: log time changed`);
    const dir = join(work, "expected");
    mkdirSync(dir, { recursive: true });
    const corrupt = (input, output) => run(["corrupt", "--type", f, "--severity", v[`${f}.severity`],
      "--rng", "numpy", "--seed", v[`${f}.seed`], "--in", input, "--out", output]);
    if (tp.type === "sensor_msgs/msg/CompressedImage") {
      const input = join(dir, `in_${compared}.jpg`), expected = join(dir, `out_${compared}.jpg`);
      writeFileSync(input, src.data);
      corrupt(input, expected);
      if (dst.format !== src.format) fail(`${topic} frame ${i}: format ${dst.format}`);
      if (!same(readFileSync(expected), dst.data)) {
        writeFileSync(join(dir, `got_${compared}.jpg`), dst.data);
        fail(`${topic} frame ${i}: JPEG differs from faultline corrupt's (${expected} vs got_${compared}.jpg)`);
      }
    } else {
      const rgb = new Uint8Array(W * H * 3);
      const bgr = src.encoding === "bgr8";
      for (let y = 0; y < H; y++) {
        for (let x = 0; x < W; x++) {
          const s = y * src.step + x * 3, d = (y * W + x) * 3;
          rgb[d] = src.data[s + (bgr ? 2 : 0)];
          rgb[d + 1] = src.data[s + 1];
          rgb[d + 2] = src.data[s + (bgr ? 0 : 2)];
        }
      }
      const input = join(dir, `in_${compared}.ppm`), expected = join(dir, `out_${compared}.ppm`);
      writeFileSync(input, ppm(W, H, rgb));
      corrupt(input, expected);
      const e = readPpm(expected);
      if (dst.encoding !== src.encoding || dst.step !== src.step || dst.width !== W || dst.height !== H) {
        fail(`${topic} frame ${i}: layout changed`);
      }
      for (let y = 0; y < H; y++) {
        for (let x = 0; x < W; x++) {
          const s = y * dst.step + x * 3, d = (y * W + x) * 3;
          const got = [dst.data[s + (bgr ? 2 : 0)], dst.data[s + 1], dst.data[s + (bgr ? 0 : 2)]];
          if (got[0] !== e.rgb[d] || got[1] !== e.rgb[d + 1] || got[2] !== e.rgb[d + 2]) {
            fail(`${topic} frame ${i}: pixel (${x}, ${y}) = ${got}, faultline corrupt gives ${[...e.rgb.subarray(d, d + 3)]}`);
          }
        }
        for (let p = W * 3; p < dst.step; p++) {
          if (dst.data[y * dst.step + p] !== 0xa5) fail(`${topic} frame ${i}: row padding changed`);
        }
      }
    }
    if (same(src.data, dst.data)) fail(`${topic} frame ${i}: unchanged`);
    compared++;
  }
  const yaml = readFileSync(join(outDir, "metadata.yaml"), "utf8");
  if (!yaml.includes("/faultline/faults") || !yaml.includes("out_bag_0.mcap")) fail("metadata.yaml lacks the faults topic or file");
  console.log(`bag corrupt check: ${a.messages.length} input messages, ${b.messages.length} output messages, ` +
              `${compared} faulted frames equal to faultline corrupt, pass-through byte-identical`);
}

main().catch((e) => fail(e.stack ?? String(e)));
