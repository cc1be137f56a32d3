// The MCAP reference implementation reads what dpc's MCAP writer (common/dpc/record/mcap.h)
// makes: @mcap/core's indexed reader (by the summary, chunk and message indexes, CRCs checked)
// and its stream reader (record by record), with @mcap/support's zstd and lz4 decompressors.
//
//   node read_with_mcap_core.mjs --writer <dpc_mcap_sample> --modules <node_modules> --work <dir>
// Exit 0 if every file reads back as expected.json says, 1 with the first difference otherwise.
import { spawnSync } from "node:child_process";
import { mkdtempSync, readFileSync, rmSync } from "node:fs";
import { open } from "node:fs/promises";
import { createRequire } from "node:module";
import { join } from "node:path";
import { tmpdir } from "node:os";

const args = Object.fromEntries(
  process.argv.slice(2).reduce((pairs, a, i, all) => (a.startsWith("--") ? [...pairs, [a.slice(2), all[i + 1]]] : pairs), []));
const require = createRequire(join(args.modules, "noop.js"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { loadDecompressHandlers } = require("@mcap/support");

const work = mkdtempSync(join(args.work ?? tmpdir(), "dpc-mcap-"));
let failures = 0;
const check = (ok, what) => {
  console.log(`${ok ? "ok" : "FAIL"}: ${what}`);
  if (!ok) failures += 1;
};

try {
  const written = spawnSync(args.writer, [work], { encoding: "utf8" });
  if (written.status !== 0) throw new Error(`${args.writer} failed: ${written.stderr}`);
  const expected = JSON.parse(readFileSync(join(work, "expected.json"), "utf8"));
  const decompressHandlers = await loadDecompressHandlers();
  const hex = (bytes) => Buffer.from(bytes).toString("hex");
  const sameMessages = (read, file, how) => {
    const first = read.findIndex((m, i) => {
      const e = expected.messages[i];
      return !e || m.topic !== e.topic || m.sequence !== e.sequence || m.log_time !== e.log_time ||
        m.publish_time !== e.publish_time || m.data !== e.data;
    });
    check(read.length === expected.messages.length && first === -1,
      `${file} (${how}): ${read.length} messages of ${expected.messages.length}, in order, every field and payload byte as written` +
      (first >= 0 ? ` — first difference at message ${first}: ${JSON.stringify(read[first]).slice(0, 200)}` : ""));
  };

  for (const file of expected.files) {
    const path = join(work, file);
    // Indexed: by the footer, summary, chunk indexes and message indexes.
    const handle = await open(path, "r");
    const readable = {
      size: async () => BigInt((await handle.stat()).size),
      read: async (offset, length) => {
        const buffer = Buffer.alloc(Number(length));
        await handle.read(buffer, 0, Number(length), Number(offset));
        return buffer;
      },
    };
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    check(reader.header.library === expected.library, `${file}: header library "${reader.header.library}"`);
    const topics = [...reader.channelsById.values()].map((c) => c.topic).sort();
    check(JSON.stringify(topics) === JSON.stringify(Object.keys(expected.schemas).sort()), `${file}: channels ${topics}`);
    for (const channel of reader.channelsById.values()) {
      const schema = reader.schemasById.get(channel.schemaId);
      check(schema?.name === expected.schemas[channel.topic] && schema?.encoding === "omgidl" && channel.messageEncoding === "cdr",
        `${file}: ${channel.topic} has schema ${schema?.name} (${schema?.encoding}), encoding ${channel.messageEncoding}`);
    }
    check(reader.statistics?.messageCount === BigInt(expected.messages.length) && reader.chunkIndexes.length > 1 &&
      reader.statistics?.chunkCount === reader.chunkIndexes.length,
      `${file}: statistics ${reader.statistics?.messageCount} messages, ${reader.chunkIndexes.length} chunk indexes`);
    const read = [];
    for await (const m of reader.readMessages()) {
      read.push({ topic: reader.channelsById.get(m.channelId).topic, sequence: m.sequence,
        log_time: String(m.logTime), publish_time: String(m.publishTime), data: hex(m.data) });
    }
    sameMessages(read, file, "indexed reader");
    const metadata = {};
    for await (const m of reader.readMetadata()) metadata[m.name] = Object.fromEntries(m.metadata);
    const canonical = (value) => JSON.stringify(value, (key, v) =>
      v && typeof v === "object" && !Array.isArray(v) ? Object.fromEntries(Object.entries(v).sort()) : v);
    check(canonical(metadata) === canonical(expected.metadata), `${file}: metadata ${canonical(metadata)}`);
    await handle.close();

    // Streamed: record by record from the start, CRCs validated.
    const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
    stream.append(readFileSync(path));
    const channels = new Map();
    const streamed = [];
    let footer = false;
    for (let record; (record = stream.nextRecord()); ) {
      if (record.type === "Channel") channels.set(record.id, record.topic);
      if (record.type === "Message") {
        streamed.push({ topic: channels.get(record.channelId), sequence: record.sequence,
          log_time: String(record.logTime), publish_time: String(record.publishTime), data: hex(record.data) });
      }
      if (record.type === "Footer") footer = true;
    }
    check(stream.done() && footer, `${file}: the stream reader reaches the footer`);
    sameMessages(streamed, file, "stream reader");
  }
} catch (error) {
  check(false, `reading threw: ${error.stack ?? error}`);
} finally {
  rmSync(work, { recursive: true, force: true });
}
console.log(failures ? `FAILED: ${failures} check(s)` : "PASS");
process.exit(failures ? 1 : 0);
