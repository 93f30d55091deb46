// Independent check of an MCAP log with the ecosystem's own JavaScript libraries: @mcap/core
// (container: footer, summary, chunk and summary CRCs, message indexes), fzstd (zstd chunks),
// @foxglove/rosmsg (ros2msg schemas) and @foxglove/rosmsg2-serialization (CDR messages).
//
//   node web/test/mcap_read.mjs FILE.mcap [--json OUT.json] [--allow-truncated]
//
// 1. Opens FILE with McapIndexedReader (validates header, footer, summary section and its CRC,
//    chunk CRCs, message indexes). With --allow-truncated, a file the indexed reader refuses (e.g.
//    a writer killed by SIGKILL: no summary, no footer, a partial last chunk) is read instead with
//    McapStreamReader record by record over the bytes that are there ("indexed": false).
//    In every case the whole file is also streamed once in file order: that pass checks per-channel
//    log_time order and, for an indexed file, that the message indexes list every message written.
// 2. Decodes EVERY message of every channel whose schema is "ros2msg" with a rosmsg2-serialization
//    MessageReader built from @foxglove/rosmsg's parse(text, {ros2: true}); a throw, or bytes left
//    over after the message (beyond <= 3 zero bytes of padding to a 4-byte multiple), is a failure.
// 3. Checks profile "ros2", message_encoding "cdr", channel metadata "offered_qos_profiles",
//    non-decreasing log_time per channel, and (indexed) Statistics against the counted messages.
// 4. Prints one JSON object (also written to --json OUT). Exit 0: no problems and no decode
//    failures; 1: problems or decode failures; 2: bad usage or a file that cannot be read at all.
import fs from 'node:fs';
import { McapIndexedReader, McapStreamReader, Opcode } from '@mcap/core';
import { decompress as zstdDecompress } from 'fzstd';
import { parse as parseMsgDefinition } from '@foxglove/rosmsg';
import { MessageReader } from '@foxglove/rosmsg2-serialization';

const USAGE = 'usage: node web/test/mcap_read.mjs FILE.mcap [--json OUT.json] [--allow-truncated]';
const MAX_LISTED_DECODE_FAILURES = 50; // the count is always exact; only the listing is capped
const STREAM_READ_BYTES = 4 << 20; // piece size fed to McapStreamReader

/** Exit 2 with a message: bad usage or an unreadable file. */
function fatal(message) {
  console.error(`mcap_read: ${message}`);
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { file: undefined, json: undefined, allowTruncated: false };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--json') {
      if (i + 1 >= argv.length) fatal(`--json needs a file name\n${USAGE}`);
      opts.json = argv[++i];
    } else if (a === '--allow-truncated') {
      opts.allowTruncated = true;
    } else if (a === '-h' || a === '--help') {
      console.log(USAGE);
      process.exit(0);
    } else if (a.startsWith('--')) {
      fatal(`unknown option ${a}\n${USAGE}`);
    } else if (opts.file === undefined) {
      opts.file = a;
    } else {
      fatal(`more than one input file\n${USAGE}`);
    }
  }
  if (opts.file === undefined) fatal(USAGE);
  return opts;
}

/** The IReadable that @mcap/core's indexed reader wants: size() and read(offset, length). */
class FileReadable {
  #handle;
  #size;
  constructor(handle, size) {
    this.#handle = handle;
    this.#size = size;
  }
  static async open(path) {
    const handle = await fs.promises.open(path, 'r');
    const { size } = await handle.stat();
    return new FileReadable(handle, BigInt(size));
  }
  async size() {
    return this.#size;
  }
  async read(offset, length) {
    if (offset < 0n || length < 0n || offset + length > this.#size) {
      throw new Error(`read of ${length} bytes at ${offset} is outside the file (${this.#size} bytes)`);
    }
    const buffer = new Uint8Array(Number(length));
    let done = 0;
    while (done < buffer.byteLength) {
      const { bytesRead } = await this.#handle.read(buffer, done, buffer.byteLength - done,
        Number(offset) + done);
      if (bytesRead === 0) throw new Error(`unexpected end of file at ${Number(offset) + done}`);
      done += bytesRead;
    }
    return buffer;
  }
  async close() {
    await this.#handle.close();
  }
}

/** The decompress handler both readers get; fzstd writes into a buffer of the announced size. */
const decompressHandlers = {
  zstd: (buffer, decompressedSize) => zstdDecompress(buffer, new Uint8Array(Number(decompressedSize))),
};

/** CRC-32 (ISO-HDLC, the one MCAP uses), for the data section CRC the indexed reader leaves unchecked. */
const CRC_TABLE = Uint32Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
function crc32Update(crc, bytes) {
  let c = crc;
  for (let i = 0; i < bytes.length; i++) c = CRC_TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return c;
}

/** DataEnd's data_section_crc: CRC of every byte before the DataEnd record. */
async function dataSectionCrc(readable, end) {
  let crc = 0xffffffff;
  for (let offset = 0n; offset < end; offset += BigInt(STREAM_READ_BYTES)) {
    const length = end - offset < BigInt(STREAM_READ_BYTES) ? end - offset : BigInt(STREAM_READ_BYTES);
    crc = crc32Update(crc, await readable.read(offset, length));
  }
  return (crc ^ 0xffffffff) >>> 0;
}

/** Decoded message -> plain JSON: BigInt as string, typed arrays as arrays, NaN/Inf as strings. */
function toJson(value) {
  if (typeof value === 'bigint') return value.toString();
  if (typeof value === 'number') return Number.isFinite(value) ? value : String(value);
  if (ArrayBuffer.isView(value)) return Array.from(value, toJson);
  if (Array.isArray(value)) return value.map(toJson);
  if (value instanceof Map) return Object.fromEntries([...value].map(([k, v]) => [k, toJson(v)]));
  if (value !== null && typeof value === 'object') {
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, toJson(v)]));
  }
  return value;
}

/**
 * Everything learnt about the file, filled by the reading passes: schemas and channels by id, a
 * per-channel tally of the decoded messages, the problems and the decode failures.
 */
class Check {
  schemas = new Map(); // id -> Schema record
  channels = new Map(); // id -> Channel record
  tallies = new Map(); // channel id -> {count, first/last log time, first/last decoded message}
  readers = new Map(); // schema id -> {reader} | {error}
  problems = [];
  decodeFailures = [];
  decodeFailureCount = 0;
  chunkCompression = {}; // compression name ("" = none) -> number of chunks

  problem(text) {
    if (!this.problems.includes(text)) this.problems.push(text);
  }

  addSchema(schema) {
    this.schemas.set(schema.id, schema);
  }

  addChannel(channel) {
    this.channels.set(channel.id, channel);
  }

  /** The MessageReader for a ros2msg schema, built once; undefined for other encodings. */
  readerFor(schemaId) {
    if (this.readers.has(schemaId)) return this.readers.get(schemaId);
    const schema = this.schemas.get(schemaId);
    let entry;
    if (!schema) {
      entry = { error: `schema ${schemaId} not found` };
    } else if (schema.encoding !== 'ros2msg') {
      entry = { error: `schema ${schemaId} (${schema.name}) is encoded "${schema.encoding}", not "ros2msg"` };
    } else {
      try {
        const text = new TextDecoder('utf-8', { fatal: true }).decode(schema.data);
        entry = { reader: new MessageReader(parseMsgDefinition(text, { ros2: true })) };
      } catch (error) {
        entry = { error: `schema ${schemaId} (${schema.name}) does not parse as ros2msg: ${error.message}` };
      }
    }
    if (entry.error) this.problem(entry.error);
    this.readers.set(schemaId, entry);
    return entry;
  }

  decodeFailure(channel, message, error) {
    this.decodeFailureCount++;
    if (this.decodeFailures.length < MAX_LISTED_DECODE_FAILURES) {
      this.decodeFailures.push({
        channel: message.channelId,
        topic: channel?.topic,
        log_time_ns: message.logTime.toString(),
        sequence: message.sequence,
        error,
      });
    }
  }

  /** Decodes one message and adds it to its channel's tally. */
  consume(message) {
    const channel = this.channels.get(message.channelId);
    let tally = this.tallies.get(message.channelId);
    if (!tally) {
      tally = { count: 0, first: undefined, last: undefined, firstMessage: undefined, lastMessage: undefined };
      this.tallies.set(message.channelId, tally);
    }
    tally.count++;
    tally.first ??= message.logTime;
    tally.last = message.logTime;

    let decoded;
    if (!channel) {
      this.decodeFailure(channel, message, `no channel record for id ${message.channelId}`);
    } else if (channel.schemaId === 0) {
      this.decodeFailure(channel, message, 'channel has no schema (schema id 0)');
    } else {
      const { reader, error } = this.readerFor(channel.schemaId);
      if (!reader) {
        this.decodeFailure(channel, message, error);
      } else {
        try {
          decoded = reader.readMessage(message.data);
          const leftover = checkConsumed(message.data, reader.lastReadByteLength());
          if (leftover) {
            this.decodeFailure(channel, message, leftover);
            decoded = undefined;
          }
        } catch (error) {
          this.decodeFailure(channel, message, `decode error: ${error.message}`);
        }
      }
    }
    if (decoded !== undefined) {
      const json = toJson(decoded);
      if (tally.firstMessage === undefined) tally.firstMessage = json;
      tally.lastMessage = json;
    }
  }
}

/**
 * Did the CDR reader consume exactly the message? Returns undefined when it did, or when what is
 * left is only padding to a 4-byte multiple (at most 3 zero bytes; RTPS serializers may add it and
 * then note its length in the low two bits of the encapsulation options, which must agree when
 * set); otherwise a description of the leftover.
 */
function checkConsumed(data, consumed) {
  const leftover = data.byteLength - consumed;
  if (leftover === 0) return undefined;
  if (leftover < 0) return `CDR reader read ${consumed} bytes past a ${data.byteLength}-byte message`;
  const tail = data.subarray(consumed);
  const optionsPadding = data[3] & 0x3; // encapsulation options: bytes 2-3 of the header
  const isPadding = leftover <= 3 && data.byteLength % 4 === 0 && tail.every((b) => b === 0) &&
    (optionsPadding === 0 || optionsPadding === leftover);
  return isPadding ? undefined
    : `${leftover} bytes left over after decoding (${consumed} of ${data.byteLength} consumed)`;
}

/**
 * Streams the whole file through McapStreamReader in file order. `onRecord` sees every record
 * (chunk contents included). Returns {complete, error, header, unparsedBytes, records}: complete is
 * true when the footer and the closing magic were reached.
 */
async function streamFile(path, onRecord) {
  // includeChunks: each Chunk record is yielded too, before the records it holds.
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true, includeChunks: true });
  const handle = await fs.promises.open(path, 'r');
  const result = { complete: false, error: undefined, header: undefined, unparsedBytes: 0, records: 0 };
  try {
    const buffer = new Uint8Array(STREAM_READ_BYTES);
    for (;;) {
      const { bytesRead } = await handle.read(buffer, 0, buffer.byteLength, null);
      if (bytesRead === 0) break;
      reader.append(buffer.subarray(0, bytesRead));
      for (let record; (record = reader.nextRecord()); ) {
        result.records++;
        if (record.type === 'Header') result.header = record;
        onRecord(record);
      }
      if (reader.done()) break;
    }
    result.complete = reader.done();
    result.unparsedBytes = result.complete ? 0 : reader.bytesRemaining();
  } catch (error) {
    result.error = error.message;
  } finally {
    await handle.close();
  }
  return result;
}

/** Checks the SummaryOffset records: each group must lie in the summary and hold only its opcode. */
async function checkSummaryOffsets(readable, reader, check) {
  const summaryStart = reader.footer.summaryStart;
  const summaryEnd = reader.footer.summaryOffsetStart !== 0n ? reader.footer.summaryOffsetStart
    : (await readable.size()) - 8n /* magic */ - 29n /* footer record */;
  for (const offset of reader.summaryOffsetsByOpcode.values()) {
    const name = Object.keys(Opcode).find((k) => Opcode[k] === offset.groupOpcode) ?? `0x${offset.groupOpcode.toString(16)}`;
    if (offset.groupStart < summaryStart || offset.groupStart + offset.groupLength > summaryEnd) {
      check.problem(`summary offset for ${name} [${offset.groupStart}, +${offset.groupLength}) lies outside the summary section`);
      continue;
    }
    // Walk the group's records by their (opcode, uint64 length) prefixes.
    const bytes = await readable.read(offset.groupStart, offset.groupLength);
    let pos = 0;
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    while (pos + 9 <= bytes.byteLength) {
      const opcode = view.getUint8(pos);
      if (opcode !== offset.groupOpcode) {
        check.problem(`summary offset group ${name} holds a record with opcode 0x${opcode.toString(16)}`);
        break;
      }
      pos += 9 + Number(view.getBigUint64(pos + 1, true));
    }
    if (pos !== bytes.byteLength && pos + 9 > bytes.byteLength) {
      check.problem(`summary offset group ${name} does not end on a record boundary`);
    }
  }
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  let size;
  try {
    size = fs.statSync(opts.file).size;
    fs.accessSync(opts.file, fs.constants.R_OK);
  } catch (error) {
    fatal(`cannot read ${opts.file}: ${error.message}`);
  }

  const check = new Check();
  const out = {
    file: opts.file,
    size_bytes: size,
    indexed: false,
    profile: undefined,
    library: undefined,
    complete: undefined, // footer and closing magic reached by the streaming pass
    indexed_error: undefined,
    statistics: undefined,
    // CRCs: MCAP lets a writer store 0 for "not computed", and the readers then skip the check.
    crc: { summary: undefined, data_section: undefined, chunks_checked: 0, chunks_without_crc: 0 },
    summary_offset_groups: undefined,
    chunk_count: 0,
    chunk_compression: check.chunkCompression,
    channels: [],
    decode_failures: check.decodeFailures,
    decode_failure_count: 0,
    problems: check.problems,
  };

  // --- 1a. The indexed read: the whole file's structure as the summary describes it. ---
  const readable = await FileReadable.open(opts.file);
  let indexed;
  try {
    indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  } catch (error) {
    out.indexed_error = error.message;
  }

  if (indexed) {
    out.indexed = true;
    out.profile = indexed.header.profile;
    out.library = indexed.header.library;
    out.chunk_count = indexed.chunkIndexes.length;
    for (const schema of indexed.schemasById.values()) check.addSchema(schema);
    for (const channel of indexed.channelsById.values()) check.addChannel(channel);
    try {
      // readMessages() yields in log_time order across chunks, validating chunk CRCs and that each
      // message index entry points at a Message record with that log time.
      for await (const message of indexed.readMessages({ validateCrcs: true })) check.consume(message);
    } catch (error) {
      check.problem(`indexed readMessages failed: ${error.message}`);
    }
    await checkSummaryOffsets(readable, indexed, check);
    // Initialize() checked the summary CRC when it is not 0; the data section CRC it only reads.
    out.crc.summary = indexed.footer.summaryCrc === 0 ? 'absent' : 'ok';
    if (indexed.dataSectionCrc === undefined) {
      out.crc.data_section = 'absent';
    } else {
      const crc = await dataSectionCrc(readable, indexed.dataEndOffset);
      out.crc.data_section = crc === indexed.dataSectionCrc ? 'ok' : 'mismatch';
      if (crc !== indexed.dataSectionCrc) {
        check.problem(`DataEnd data_section_crc ${indexed.dataSectionCrc} but the data section's CRC is ${crc}`);
      }
    }
    out.summary_offset_groups = [...indexed.summaryOffsetsByOpcode.keys()]
      .map((op) => Object.keys(Opcode).find((k) => Opcode[k] === op) ?? op);
  } else if (!opts.allowTruncated) {
    check.problem(`indexed read failed: ${out.indexed_error}`);
  }
  await readable.close();

  // --- 1b. The streaming read, in file order (the only read when the indexed one failed). ---
  const streamCounts = new Map(); // channel id -> messages seen by the streaming pass
  const lastLogTime = new Map(); // channel id -> last log_time in file order
  const orderFaults = new Map(); // channel id -> number of log_time decreases
  let chunksInData = 0;
  const stream = await streamFile(opts.file, (record) => {
    switch (record.type) {
      case 'Schema':
        if (!indexed) check.addSchema(record);
        break;
      case 'Channel':
        if (!indexed) check.addChannel(record);
        break;
      case 'Chunk':
        chunksInData++;
        if (record.uncompressedCrc === 0) out.crc.chunks_without_crc++;
        else out.crc.chunks_checked++; // (a mismatch throws: reported as a streaming read failure)
        check.chunkCompression[record.compression] = (check.chunkCompression[record.compression] ?? 0) + 1;
        break;
      case 'Message': {
        const id = record.channelId;
        streamCounts.set(id, (streamCounts.get(id) ?? 0) + 1);
        const previous = lastLogTime.get(id);
        if (previous !== undefined && record.logTime < previous) {
          orderFaults.set(id, (orderFaults.get(id) ?? 0) + 1);
        }
        lastLogTime.set(id, record.logTime);
        if (!indexed) check.consume(record);
        break;
      }
      default:
        break;
    }
  });
  out.complete = stream.complete;
  if (!indexed) {
    if (!stream.header) {
      fatal(`${opts.file} is not readable as MCAP: ${stream.error ?? out.indexed_error ?? 'no header record'}`);
    }
    out.profile = stream.header.profile;
    out.library = stream.header.library;
    out.unparsed_tail_bytes = stream.unparsedBytes;
    if (stream.complete) {
      // A complete file (footer reached) must be readable indexed: truncation is no excuse here.
      check.problem(`indexed read failed on a complete file: ${out.indexed_error}`);
    }
  }
  if (stream.error) check.problem(`streaming read failed: ${stream.error}`);
  if (indexed && !stream.complete && !stream.error) {
    check.problem('streaming read did not reach the footer of an indexed file');
  }

  // Chunks in the data section against the chunk indexes of the summary.
  if (!indexed) {
    out.chunk_count = chunksInData;
  } else if (!stream.error && chunksInData !== out.chunk_count) {
    check.problem(`${chunksInData} chunks in the data section but ${out.chunk_count} chunk indexes in the summary`);
  }

  // --- 3. The ros2 profile and per-channel checks. ---
  if (out.profile !== 'ros2') check.problem(`header profile is "${out.profile}", expected "ros2"`);
  for (const channel of [...check.channels.values()].sort((a, b) => a.id - b.id)) {
    const tally = check.tallies.get(channel.id) ?? { count: 0 };
    const schema = check.schemas.get(channel.schemaId);
    if (channel.messageEncoding !== 'cdr') {
      check.problem(`channel ${channel.id} (${channel.topic}) message_encoding is "${channel.messageEncoding}", expected "cdr"`);
    }
    if (!channel.metadata.has('offered_qos_profiles')) {
      check.problem(`channel ${channel.id} (${channel.topic}) has no "offered_qos_profiles" metadata`);
    }
    if (channel.schemaId !== 0 && !schema) {
      check.problem(`channel ${channel.id} (${channel.topic}) refers to missing schema ${channel.schemaId}`);
    }
    if (orderFaults.get(channel.id)) {
      check.problem(`channel ${channel.id} (${channel.topic}): log_time decreases ${orderFaults.get(channel.id)} time(s) in file order`);
    }
    if (indexed && (streamCounts.get(channel.id) ?? 0) !== tally.count) {
      check.problem(`channel ${channel.id} (${channel.topic}): ${streamCounts.get(channel.id) ?? 0} messages in the data section but ${tally.count} reachable through the message indexes`);
    }
    out.channels.push({
      id: channel.id,
      topic: channel.topic,
      schema: schema?.name ?? null,
      schema_encoding: schema?.encoding ?? null,
      encoding: channel.messageEncoding,
      count: tally.count,
      first_log_time_ns: tally.first?.toString() ?? null,
      last_log_time_ns: tally.last?.toString() ?? null,
      first_message: tally.firstMessage ?? null,
      last_message: tally.lastMessage ?? null,
    });
  }
  for (const id of check.tallies.keys()) {
    if (!check.channels.has(id)) check.problem(`messages on channel ${id}, which has no channel record`);
  }

  // Statistics (indexed files): counts per channel, totals and time range against what was read.
  if (indexed) {
    const stats = indexed.statistics;
    out.statistics = stats ? toJson({ ...stats, type: undefined }) : null;
    if (stats) checkStatistics(stats, indexed, check);
  }

  out.decode_failure_count = check.decodeFailureCount;
  const json = JSON.stringify(out, null, 2);
  console.log(json);
  if (opts.json) fs.writeFileSync(opts.json, `${json}\n`);
  process.exit(check.problems.length === 0 && check.decodeFailureCount === 0 ? 0 : 1);
}

/** Statistics record against the messages counted through the indexed reader. */
function checkStatistics(stats, indexed, check) {
  let total = 0n;
  let start;
  let end;
  for (const tally of check.tallies.values()) {
    total += BigInt(tally.count);
    if (start === undefined || tally.first < start) start = tally.first;
    if (end === undefined || tally.last > end) end = tally.last;
  }
  if (stats.messageCount !== total) {
    check.problem(`Statistics message_count ${stats.messageCount} but ${total} messages read`);
  }
  // An empty map means "not available" (spec); otherwise every channel with messages must match.
  if (stats.channelMessageCounts.size > 0) {
    const ids = new Set([...stats.channelMessageCounts.keys(), ...check.channels.keys()]);
    for (const id of ids) {
      const expected = BigInt(check.tallies.get(id)?.count ?? 0);
      const stated = stats.channelMessageCounts.get(id) ?? 0n;
      if (stated !== expected) {
        check.problem(`Statistics channel_message_counts[${id}] = ${stated} but ${expected} messages read`);
      }
    }
  }
  if (total > 0n && (stats.messageStartTime !== start || stats.messageEndTime !== end)) {
    check.problem(`Statistics time range [${stats.messageStartTime}, ${stats.messageEndTime}] but messages span [${start}, ${end}]`);
  }
  if (stats.channelCount !== indexed.channelsById.size) {
    check.problem(`Statistics channel_count ${stats.channelCount} but ${indexed.channelsById.size} channels in the summary`);
  }
  if (stats.schemaCount !== indexed.schemasById.size) {
    check.problem(`Statistics schema_count ${stats.schemaCount} but ${indexed.schemasById.size} schemas in the summary`);
  }
  if (stats.chunkCount !== indexed.chunkIndexes.length) {
    check.problem(`Statistics chunk_count ${stats.chunkCount} but ${indexed.chunkIndexes.length} chunk indexes`);
  }
}

await main();
