// Independent check of a Faultline bag with the reference TypeScript MCAP reader
// (specs/interfaces.md §3.6). Usage: node validate_mcap.mjs FILE.mcap [expected_message_count]
// Exits non-zero on any problem: indexed read with chunk CRCs, the data-section CRC (which
// @mcap/core does not check), protobuf decoding of every message with its own schema, the
// statistics count, and a full streaming pass that must reach the footer.
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { FileHandleReadable } from "@mcap/nodejs";
import { loadDecompressHandlers, protobufFromBinaryDescriptor } from "@mcap/support";
import { open, readFile } from "node:fs/promises";
import { crc32 } from "node:zlib";

async function validate(file, expected) {
  const decompressHandlers = await loadDecompressHandlers();
  const handle = await open(file, "r");
  try {
    const reader = await McapIndexedReader.Initialize({
      readable: new FileHandleReadable(handle),
      decompressHandlers,
    });
    const bytes = await readFile(file);

    const computed = crc32(bytes.subarray(0, Number(reader.dataEndOffset)));
    if (reader.dataSectionCrc !== computed) {
      throw new Error(`data section CRC: stored ${reader.dataSectionCrc}, computed ${computed}`);
    }

    const decoders = new Map();
    const perTopic = new Map();
    let count = 0;
    let lastLogTime = -1n;
    for await (const message of reader.readMessages({ validateCrcs: true })) {
      const channel = reader.channelsById.get(message.channelId);
      if (!channel) throw new Error(`message on unknown channel ${message.channelId}`);
      if (message.logTime < lastLogTime) throw new Error("messages not in log-time order");
      lastLogTime = message.logTime;
      if (channel.messageEncoding === "protobuf") {
        const schema = reader.schemasById.get(channel.schemaId);
        if (!schema || schema.encoding !== "protobuf") {
          throw new Error(`channel ${channel.topic}: protobuf without a protobuf schema`);
        }
        if (!decoders.has(schema.id)) {
          const root = protobufFromBinaryDescriptor(schema.data);
          decoders.set(schema.id, root.lookupType(schema.name));
        }
        decoders.get(schema.id).decode(message.data);
      }
      perTopic.set(channel.topic, (perTopic.get(channel.topic) ?? 0) + 1);
      count++;
    }
    if (reader.statistics?.messageCount !== BigInt(count)) {
      throw new Error(`statistics say ${reader.statistics?.messageCount} messages, read ${count}`);
    }
    for (const [id, n] of reader.statistics.channelMessageCounts) {
      const topic = reader.channelsById.get(id)?.topic;
      if ((perTopic.get(topic) ?? 0) !== Number(n)) {
        throw new Error(`statistics for ${topic}: ${n}, read ${perTopic.get(topic) ?? 0}`);
      }
    }
    if (expected !== undefined && count !== Number(expected)) {
      throw new Error(`${count} messages, expected ${expected}`);
    }

    const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
    stream.append(bytes);
    let streamed = 0;
    for (let record; (record = stream.nextRecord()); ) {
      if (record.type === "Message") streamed++;
    }
    if (!stream.done()) throw new Error("stream reader did not reach the footer");
    if (streamed !== count) throw new Error(`stream reader saw ${streamed} messages, indexed ${count}`);

    console.log(`ok: ${file}: ${count} messages, ${reader.chunkIndexes.length} chunks, ` +
                `${reader.schemasById.size} schemas, ${perTopic.size} topics`);
  } finally {
    await handle.close();
  }
}

const [file, expected] = process.argv.slice(2);
if (!file) {
  console.error("usage: node validate_mcap.mjs FILE.mcap [expected_message_count]");
  process.exit(2);
}
try {
  await validate(file, expected);
} catch (error) {
  console.error(`FAIL: ${file}: ${error.message}`);
  process.exit(1);
}
