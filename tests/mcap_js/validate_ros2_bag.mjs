// Independent check of a rosbag2 directory written by `faultline bag convert --format ros2`, with the TypeScript
// readers Foxglove uses for ROS 2 data (no Faultline code, no ROS 2 install):
//   - metadata.yaml (yaml) agrees with the MCAP file: version, storage, file list, per-topic types and counts,
//     total count, start time and duration, offered_qos_profiles (transient local on /tf_static);
//   - the MCAP file (@mcap/core, CRCs checked) has profile ros2, cdr channels and ros2msg schemas;
//   - every message is decoded with a reader built from its channel's own embedded schema (@foxglove/rosmsg
//     parse + @foxglove/rosmsg2-serialization MessageReader) and must consume its bytes exactly;
//   - fields: image format jpeg with JPEG SOI/EOI bytes, frame_ids = the channel name of the topic, stamps
//     increasing per topic, CameraInfo rectified (plumb_bob, d = 0, R = I, P = [K | 0]), TF frames, the
//     DELETEALL first marker, DiagnosticArray hardware ids; with --dataroot, every clean image is byte-equal to
//     its nuScenes file and every K and /tf_static transform is a calibrated_sensor of that channel.
// Usage: node validate_ros2_bag.mjs BAG_DIR [--dataroot D --version V] [--expect TOPIC=COUNT]...
// Prints one JSON summary line; exits 1 on the first problem, 2 on bad usage.
import { McapIndexedReader } from "@mcap/core";
import { FileHandleReadable } from "@mcap/nodejs";
import { loadDecompressHandlers } from "@mcap/support";
import { parse as parseMsg } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { parse as parseYaml } from "yaml";
import { open, readFile } from "node:fs/promises";
import { existsSync } from "node:fs";
import path from "node:path";

function fail(message) {
  throw new Error(message);
}

function parseArgs(argv) {
  const args = { dir: undefined, dataroot: undefined, version: "v1.0-mini", expect: new Map() };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === "--dataroot") args.dataroot = argv[++i];
    else if (a === "--version") args.version = argv[++i];
    else if (a === "--expect") {
      const [topic, n] = (argv[++i] ?? "").split("=");
      if (!topic || n === undefined) fail(`--expect wants TOPIC=COUNT, got ${argv[i]}`);
      args.expect.set(topic, Number(n));
    } else if (!args.dir) args.dir = a;
    else fail(`unexpected argument ${a}`);
  }
  if (!args.dir) fail("usage: validate_ros2_bag.mjs BAG_DIR [--dataroot D --version V] [--expect TOPIC=COUNT]...");
  return args;
}

// nuScenes tables of the dataroot: per channel the calibrated sensors, and image files by channel + timestamp.
async function loadDataset(dataroot, version) {
  const table = async (name) => JSON.parse(await readFile(path.join(dataroot, version, `${name}.json`), "utf8"));
  const sensors = new Map((await table("sensor")).map((s) => [s.token, s.channel]));
  const calibrations = new Map();  // token -> {channel, k, translation, rotation}
  for (const c of await table("calibrated_sensor")) {
    const channel = sensors.get(c.sensor_token);
    if (!channel?.startsWith("CAM_")) continue;
    calibrations.set(c.token, {
      channel, k: c.camera_intrinsic.flat(), translation: c.translation, rotation: c.rotation,
    });
  }
  const files = new Map();  // `${channel}@${timestamp_us}` -> filename
  for (const sd of await table("sample_data")) {
    const cal = calibrations.get(sd.calibrated_sensor_token);
    if (cal) files.set(`${cal.channel}@${sd.timestamp}`, sd.filename);
  }
  const byChannel = new Map();
  for (const cal of calibrations.values()) {
    if (!byChannel.has(cal.channel)) byChannel.set(cal.channel, []);
    byChannel.get(cal.channel).push(cal);
  }
  return { dataroot, byChannel, files };
}

const near = (a, b) => Math.abs(a - b) <= 1e-9 * Math.max(1, Math.abs(a), Math.abs(b));
const stampNs = (t) => BigInt(t.sec) * 1000000000n + BigInt(t.nanosec);

// "/CAM_FRONT/image_rect_compressed" or "/faulty/CAM_FRONT/camera_info" -> "CAM_FRONT".
function channelOfTopic(topic) {
  const parts = topic.split("/").filter(Boolean);
  return parts.length >= 2 ? parts[parts.length - 2] : undefined;
}

async function validate(args) {
  // Integers as BigInt: nanosecond stamps do not fit a double.
  const meta = parseYaml(await readFile(path.join(args.dir, "metadata.yaml"), "utf8"), { intAsBigInt: true })
    ?.rosbag2_bagfile_information;
  if (!meta) fail("metadata.yaml: no rosbag2_bagfile_information");
  if (meta.version !== 5n) fail(`metadata.yaml: version ${meta.version}, expected 5 (what Humble writes)`);
  if (meta.storage_identifier !== "mcap") fail(`metadata.yaml: storage_identifier ${meta.storage_identifier}`);
  if (meta.relative_file_paths?.length !== 1) fail("metadata.yaml: expected one relative file path");
  const mcapPath = path.join(args.dir, meta.relative_file_paths[0]);
  if (!existsSync(mcapPath)) fail(`metadata.yaml names ${meta.relative_file_paths[0]}, which does not exist`);
  if (meta.files?.[0]?.path !== meta.relative_file_paths[0]) fail("metadata.yaml: files[0].path differs");
  const dataset = args.dataroot ? await loadDataset(args.dataroot, args.version) : undefined;

  const handle = await open(mcapPath, "r");
  try {
    const reader = await McapIndexedReader.Initialize({
      readable: new FileHandleReadable(handle),
      decompressHandlers: await loadDecompressHandlers(),
    });
    if (reader.header.profile !== "ros2") fail(`MCAP profile "${reader.header.profile}", expected ros2`);

    const readers = new Map();  // channel id -> MessageReader from the channel's own schema
    for (const channel of reader.channelsById.values()) {
      const schema = reader.schemasById.get(channel.schemaId);
      if (channel.messageEncoding !== "cdr") fail(`${channel.topic}: message encoding ${channel.messageEncoding}`);
      if (!schema || schema.encoding !== "ros2msg") fail(`${channel.topic}: schema is not ros2msg`);
      if (!channel.metadata.get("offered_qos_profiles")) fail(`${channel.topic}: no offered_qos_profiles`);
      const text = new TextDecoder().decode(schema.data);
      readers.set(channel.id, { schema: schema.name, reader: new MessageReader(parseMsg(text, { ros2: true })) });
    }

    // Clean images are byte-equal to the dataset's files. With faults, the faulted frames are under /faulty/, or,
    // when the bag keeps no clean stream (no /faulty/ topics), on the plain camera topics.
    const topics = [...reader.channelsById.values()].map((c) => c.topic);
    const hasFaults = topics.includes("/faultline/faults");
    const hasFaultyNs = topics.some((t) => t.startsWith("/faulty/"));
    const cleanTopic = (topic) => !topic.startsWith("/faulty/") && (!hasFaults || hasFaultyNs);

    const counts = new Map();
    const lastStamp = new Map();
    let total = 0, first, last, imagesCompared = 0, calibrationsChecked = 0;
    for await (const message of reader.readMessages({ validateCrcs: true })) {
      const channel = reader.channelsById.get(message.channelId);
      const { schema, reader: cdr } = readers.get(message.channelId);
      const where = `${channel.topic} message ${counts.get(channel.topic) ?? 0}`;
      const msg = cdr.readMessage(message.data);
      if (cdr.lastReadHadTrailingBytes()) fail(`${where}: ${schema} decode left trailing bytes`);
      counts.set(channel.topic, (counts.get(channel.topic) ?? 0) + 1);
      total++;
      first ??= message.logTime;
      last = message.logTime;

      const checkStamp = (header) => {
        const ns = stampNs(header.stamp);
        if (ns > message.logTime) fail(`${where}: stamp ${ns} after log time ${message.logTime}`);
        const prev = lastStamp.get(channel.topic);
        if (prev !== undefined && ns <= prev) fail(`${where}: stamp ${ns} not after ${prev}`);
        lastStamp.set(channel.topic, ns);
      };
      const cameraChannel = channelOfTopic(channel.topic);
      if (schema === "sensor_msgs/msg/CompressedImage") {
        if (msg.format !== "jpeg") fail(`${where}: format ${msg.format}`);
        if (msg.header.frame_id !== cameraChannel) fail(`${where}: frame_id ${msg.header.frame_id}`);
        const d = msg.data;
        if (d.length < 4 || d[0] !== 0xff || d[1] !== 0xd8 || d[d.length - 2] !== 0xff || d[d.length - 1] !== 0xd9) {
          fail(`${where}: not a JPEG (SOI/EOI)`);
        }
        checkStamp(msg.header);
        if (dataset && cleanTopic(channel.topic)) {
          const us = stampNs(msg.header.stamp) / 1000n;
          const file = dataset.files.get(`${msg.header.frame_id}@${us}`);
          if (!file) fail(`${where}: no sample_data for ${msg.header.frame_id} at ${us} us`);
          const bytes = await readFile(path.join(dataset.dataroot, file));
          if (!bytes.equals(Buffer.from(d.buffer, d.byteOffset, d.length))) fail(`${where}: bytes differ from ${file}`);
          imagesCompared++;
        }
      } else if (schema === "sensor_msgs/msg/CameraInfo") {
        if (msg.header.frame_id !== cameraChannel) fail(`${where}: frame_id ${msg.header.frame_id}`);
        checkStamp(msg.header);
        if (msg.distortion_model !== "plumb_bob" || msg.d.length !== 5 || msg.d.some((v) => v !== 0)) {
          fail(`${where}: expected plumb_bob with five zero coefficients`);
        }
        const k = Array.from(msg.k), p = Array.from(msg.p), r = Array.from(msg.r);
        if (k.length !== 9 || p.length !== 12 || r.length !== 9) fail(`${where}: k/r/p sizes`);
        if (r.some((v, i) => v !== (i % 4 === 0 ? 1 : 0))) fail(`${where}: R is not the identity`);
        for (let row = 0; row < 3; row++) {
          for (let col = 0; col < 4; col++) {
            if (p[row * 4 + col] !== (col < 3 ? k[row * 3 + col] : 0)) fail(`${where}: P is not [K | 0]`);
          }
        }
        if (dataset) {
          const cals = dataset.byChannel.get(cameraChannel) ?? [];
          if (!cals.some((c) => c.k.every((v, i) => near(v, k[i])))) fail(`${where}: K matches no calibrated_sensor`);
          calibrationsChecked++;
        }
      } else if (schema === "tf2_msgs/msg/TFMessage") {
        if (msg.transforms.length === 0) fail(`${where}: empty TFMessage`);
        for (const t of msg.transforms) {
          if (channel.topic === "/tf_static") {
            if (t.header.frame_id !== "base_link" || !t.child_frame_id.startsWith("CAM_")) {
              fail(`${where}: static transform ${t.header.frame_id} -> ${t.child_frame_id}`);
            }
            if (dataset) {
              const q = t.transform.rotation, v = t.transform.translation;
              const ok = (dataset.byChannel.get(t.child_frame_id) ?? []).some(
                (c) => near(c.translation[0], v.x) && near(c.translation[1], v.y) && near(c.translation[2], v.z) &&
                  near(c.rotation[0], q.w) && near(c.rotation[1], q.x) && near(c.rotation[2], q.y) &&
                  near(c.rotation[3], q.z));
              if (!ok) fail(`${where}: ${t.child_frame_id} matches no calibrated_sensor`);
            }
          } else if (t.header.frame_id !== "map" || t.child_frame_id !== "base_link") {
            fail(`${where}: transform ${t.header.frame_id} -> ${t.child_frame_id}`);
          }
        }
        if (channel.topic === "/tf_static") {
          const children = new Set(msg.transforms.map((t) => t.child_frame_id));
          if (children.size !== msg.transforms.length) fail(`${where}: a camera twice in /tf_static`);
        }
      } else if (schema === "visualization_msgs/msg/MarkerArray") {
        if (msg.markers.length === 0 || msg.markers[0].action !== 3) fail(`${where}: first marker is not DELETEALL`);
        for (const m of msg.markers.slice(1)) {
          if (m.header.frame_id !== "map" || m.type !== 1 || m.action !== 0) fail(`${where}: marker ${m.id}`);
        }
      } else if (schema === "diagnostic_msgs/msg/DiagnosticArray") {
        if (msg.status.length !== 1) fail(`${where}: ${msg.status.length} statuses`);
        const s = msg.status[0];
        if (s.hardware_id !== msg.header.frame_id || !s.hardware_id.startsWith("CAM_")) fail(`${where}: hardware_id`);
        if (!s.values.some((kv) => kv.key === "action")) fail(`${where}: no action value`);
      } else {
        fail(`${where}: unexpected type ${schema}`);
      }
    }

    // metadata.yaml against what the file holds.
    if (meta.message_count !== BigInt(total)) fail(`metadata.yaml: message_count ${meta.message_count}, read ${total}`);
    if (total > 0) {
      if (meta.starting_time.nanoseconds_since_epoch !== first) fail("metadata.yaml: starting_time");
      if (meta.duration.nanoseconds !== last - first) fail("metadata.yaml: duration");
      const file = meta.files[0];
      if (file.starting_time.nanoseconds_since_epoch !== first || file.duration.nanoseconds !== last - first ||
          file.message_count !== BigInt(total)) {
        fail("metadata.yaml: files[0] disagrees with the file");
      }
    }
    const metaTopics = new Map(meta.topics_with_message_count.map((t) => [t.topic_metadata.name, t]));
    if (metaTopics.size !== reader.channelsById.size) fail("metadata.yaml: topic list differs from the channels");
    for (const channel of reader.channelsById.values()) {
      const t = metaTopics.get(channel.topic) ?? fail(`metadata.yaml: no topic ${channel.topic}`);
      const schema = reader.schemasById.get(channel.schemaId);
      if (t.topic_metadata.type !== schema.name) fail(`metadata.yaml: ${channel.topic} type ${t.topic_metadata.type}`);
      if (t.topic_metadata.serialization_format !== "cdr") fail(`metadata.yaml: ${channel.topic} format`);
      if (t.topic_metadata.offered_qos_profiles !== channel.metadata.get("offered_qos_profiles")) {
        fail(`metadata.yaml: ${channel.topic} QoS differs from the channel's`);
      }
      if (t.message_count !== BigInt(counts.get(channel.topic) ?? 0)) {
        fail(`metadata.yaml: ${channel.topic} ${t.message_count} messages, read ${counts.get(channel.topic) ?? 0}`);
      }
      const qos = parseYaml(t.topic_metadata.offered_qos_profiles)[0];
      const wantDurability = channel.topic === "/tf_static" ? 1 : 2;  // transient local : volatile
      if (qos.durability !== wantDurability) fail(`${channel.topic}: durability ${qos.durability}`);
    }
    // The "rosbag2" Metadata record (what Jazzy reads from a bare .mcap): the same metadata at the same version.
    const records = [];
    for await (const record of reader.readMetadata({ name: "rosbag2" })) records.push(record);
    if (records.length !== 1) fail(`${records.length} "rosbag2" metadata records, expected 1`);
    const embedded = parseYaml(records[0].metadata.get("serialized_metadata") ?? "", { intAsBigInt: true });
    if (embedded?.version !== meta.version || embedded?.message_count !== meta.message_count ||
        embedded?.topics_with_message_count?.length !== meta.topics_with_message_count.length) {
      fail("the rosbag2 metadata record disagrees with metadata.yaml");
    }
    for (const [topic, n] of args.expect) {
      if ((counts.get(topic) ?? 0) !== n) fail(`${topic}: ${counts.get(topic) ?? 0} messages, expected ${n}`);
    }
    return {
      ok: true,
      messages: total,
      topics: Object.fromEntries([...counts].sort()),
      images_compared_with_dataset: imagesCompared,
      camera_infos_checked_against_calibration: calibrationsChecked,
    };
  } finally {
    await handle.close();
  }
}

try {
  const args = parseArgs(process.argv.slice(2));
  console.log(JSON.stringify(await validate(args)));
} catch (e) {
  console.error(`validate_ros2_bag: ${e.message}`);
  process.exit(1);
}
