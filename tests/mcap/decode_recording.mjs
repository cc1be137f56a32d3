// Decodes a recording of `dpc record` with the reference implementations only: @mcap/core reads
// the file (McapIndexedReader: footer, summary, chunk and message indexes), @foxglove/omgidl-parser
// parses each channel's schema (the IDL text stored in the file) and
// @foxglove/omgidl-serialization decodes every message's CDR payload with it.
//
//   node decode_recording.mjs --file REC.mcap --modules NODE_MODULES --out DIR
//
// Writes DIR/<topic>.jsonl: one object per message, {"log_time_ns", "publish_time_ns",
// "message"}, the message's fields as `dpc topic echo --json` names them (enums by their IDL
// name, 64-bit integers as decimal strings, sequences and arrays as arrays, NaN as null). Prints
// one JSON line with the count per topic. Exits 1 (naming the message) if any message does not
// decode or a schema is not the omgidl/cdr pair dpc writes.

import fs from "node:fs";
import path from "node:path";
import { createRequire } from "node:module";

function arg(name) {
  const i = process.argv.indexOf(name);
  if (i < 0 || i + 1 >= process.argv.length) {
    console.error(`usage: node decode_recording.mjs --file REC.mcap --modules NODE_MODULES --out DIR (missing ${name})`);
    process.exit(2);
  }
  return process.argv[i + 1];
}

const file = arg("--file");
const modules = arg("--modules");
const outDir = arg("--out");
const require = createRequire(path.join(modules, "noop.js"));  // modules: a node_modules directory
const { McapIndexedReader } = require("@mcap/core");
const { loadDecompressHandlers } = require("@mcap/support");
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");

class FileReadable {
  constructor(handle, size) {
    this.handle = handle;
    this.fileSize = size;
  }
  async size() {
    return BigInt(this.fileSize);
  }
  async read(offset, length) {
    const buffer = new Uint8Array(Number(length));
    const { bytesRead } = await this.handle.read(buffer, 0, Number(length), Number(offset));
    if (bytesRead !== Number(length)) throw new Error(`short read at ${offset}`);
    return buffer;
  }
}

function fail(message) {
  console.error(`decode_recording: ${message}`);
  process.exit(1);
}

/// A decoded value as plain JSON in dpc's naming: enums by name, BigInt as a decimal string.
function normalize(value, typeName, definitions) {
  const type = definitions.get(typeName);
  const out = {};
  for (const field of type.definitions) {
    if (field.isConstant) continue;
    out[field.name] = normalizeField(value[field.name], field, definitions);
  }
  return out;
}

function normalizeField(value, field, definitions) {
  const one = (v) => {
    if (field.enumType) {
      const e = definitions.get(field.enumType).definitions.find((c) => c.value === v);
      return e ? e.name : v;
    }
    if (field.isComplex) return normalize(v, field.type, definitions);
    if (typeof v === "bigint") return v.toString();
    if (typeof v === "number" && !Number.isFinite(v)) return null;
    return v;
  };
  if (field.isArray) return Array.from(value, one);
  return one(value);
}

const handle = await fs.promises.open(file, "r");
const { size } = await handle.stat();
const reader = await McapIndexedReader.Initialize({
  readable: new FileReadable(handle, size),
  decompressHandlers: await loadDecompressHandlers(),
});

const decoders = new Map();  // channel id → {topic, decode, definitions, root}
for (const [id, channel] of reader.channelsById) {
  const schema = reader.schemasById.get(channel.schemaId);
  if (!schema) fail(`channel ${channel.topic} has no schema`);
  if (schema.encoding !== "omgidl" || channel.messageEncoding !== "cdr") {
    fail(`channel ${channel.topic}: schema encoding ${schema.encoding}, message encoding ${channel.messageEncoding}`);
  }
  const parsed = parseIDL(new TextDecoder().decode(schema.data));
  const definitions = new Map(parsed.map((d) => [d.name, d]));
  if (!definitions.has(schema.name)) fail(`channel ${channel.topic}: schema ${schema.name} is not in its IDL`);
  decoders.set(id, {
    topic: channel.topic,
    root: schema.name,
    definitions,
    reader: new MessageReader(schema.name, parsed),
  });
}

fs.mkdirSync(outDir, { recursive: true });
const lines = new Map();
const counts = {};
for await (const message of reader.readMessages()) {
  const d = decoders.get(message.channelId);
  let decoded;
  try {
    decoded = d.reader.readMessage(message.data);
  } catch (e) {
    fail(`${d.topic} message ${message.sequence} does not decode: ${e.message}`);
  }
  const line = JSON.stringify({
    log_time_ns: message.logTime.toString(),
    publish_time_ns: message.publishTime.toString(),
    message: normalize(decoded, d.root, d.definitions),
  });
  if (!lines.has(d.topic)) lines.set(d.topic, []);
  lines.get(d.topic).push(line);
  counts[d.topic] = (counts[d.topic] ?? 0) + 1;
}
for (const [topic, topicLines] of lines) {
  fs.writeFileSync(path.join(outDir, `${topic}.jsonl`), topicLines.join("\n") + "\n");
}
await handle.close();
console.log(JSON.stringify(counts));
