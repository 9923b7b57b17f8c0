"""ROS 1 bag files whose header record is laid out as rosbag writes it, so reindex and append keep them.

rosbag (C++ ``Bag::writeFileHeaderRecord``, Python ``Bag._write_file_header_record``) pads the bag-header record's
*data* to ``4096 - header length``: 4104 bytes with the two length fields. rosbags' Writer pads the whole record to
4096, so rosbag's reindex and append, rewriting it in place, overwrite the first chunk's first 8 bytes.
:class:`Rosbag1Writer` reserves rosbag's 4104 bytes and rewrites the record in rosbag's layout on close."""
from __future__ import annotations

import struct

from rosbags.rosbag1 import Writer

from crfmap.errors import InputError

BAG_MAGIC = b"#ROSBAG V2.0\n"
FILE_HEADER_LENGTH = 4096  # rosbag's _FILE_HEADER_LENGTH: header + padding, without the two length fields
OP_FILE_HEADER = 0x03


def file_header_record(index_pos, conn_count, chunk_count) -> bytes:
    """The bag-header record exactly as rosbag record (C++) writes it: fields in std::map order, 4104 bytes."""
    fields = {"chunk_count": struct.pack("<I", chunk_count), "conn_count": struct.pack("<I", conn_count),
              "index_pos": struct.pack("<Q", index_pos), "op": bytes([OP_FILE_HEADER])}
    header = b"".join(struct.pack("<I", len(k) + 1 + len(v)) + k.encode() + b"=" + v for k, v in fields.items())
    padding = b" " * max(0, FILE_HEADER_LENGTH - len(header))
    return struct.pack("<I", len(header)) + header + struct.pack("<I", len(padding)) + padding


def parse_header_fields(header: bytes) -> dict:
    """{name: raw value} of a ROS 1 record header (length-prefixed ``name=value`` fields)."""
    fields, pos = {}, 0
    while pos < len(header):
        (size,) = struct.unpack_from("<I", header, pos)
        name, _, value = header[pos + 4: pos + 4 + size].partition(b"=")
        fields[name.decode()] = value
        pos += 4 + size
    return fields


OP_CHUNK = 0x05
CHUNK_COMPRESSIONS = ("none", "bz2", "lz4")  # what rosbag writes (and rosbags reads)
MAX_CHUNK_EXPANSION = 1000  # a compressed chunk's stated size over its stored size: laser logs compress by < 10


def check_records(path, file_size=None):
    """Walk a ROS 1 bag's top-level records (headers only); InputError naming ``path`` for one that lies: a record
    reaching past the end of the file, a chunk compression rosbag does not write, or a chunk's uncompressed ``size``
    unequal to its stored bytes (uncompressed) or over :data:`MAX_CHUNK_EXPANSION` times them (compressed)."""
    with open(path, "rb") as f:
        size = file_size if file_size is not None else f.seek(0, 2)
        f.seek(len(BAG_MAGIC))
        pos = len(BAG_MAGIC)
        while pos < size:
            lengths = f.read(4)
            if len(lengths) < 4:
                raise InputError(path, f"record at byte {pos}: cut off (truncated bag?)")
            (header_length,) = struct.unpack("<I", lengths)
            if pos + 8 + header_length > size:
                raise InputError(path, f"record at byte {pos}: a header of {header_length} bytes reaches past the "
                                       f"end of the file ({size} bytes): truncated or corrupt")
            header = f.read(header_length)
            (data_length,) = struct.unpack("<I", f.read(4))
            end = pos + 8 + header_length + data_length
            if end > size:
                raise InputError(path, f"record at byte {pos}: {data_length} bytes of data reach past the end of the "
                                       f"file ({size} bytes): truncated or corrupt")
            try:
                fields = parse_header_fields(header)
            except (struct.error, UnicodeDecodeError):
                raise InputError(path, f"record at byte {pos}: unreadable header fields") from None
            if fields.get("op") == bytes([OP_CHUNK]):
                _check_chunk(path, pos, fields, data_length)
            f.seek(end)
            pos = end


def _check_chunk(path, pos, fields, data_length):
    compression = fields.get("compression", b"").decode("ascii", "replace")
    if compression not in CHUNK_COMPRESSIONS:
        raise InputError(path, f"chunk at byte {pos}: unknown compression {compression!r} "
                               f"(rosbag writes {', '.join(CHUNK_COMPRESSIONS)})")
    raw = fields.get("size", b"")
    if len(raw) != 4:
        raise InputError(path, f"chunk at byte {pos}: no 4-byte size field")
    (stated,) = struct.unpack("<I", raw)
    if compression == "none" and stated != data_length:
        raise InputError(path, f"chunk at byte {pos}: states {stated} bytes but stores {data_length} uncompressed")
    if compression != "none" and stated > MAX_CHUNK_EXPANSION * max(data_length, 1):
        raise InputError(path, f"chunk at byte {pos}: states {stated} bytes, over {MAX_CHUNK_EXPANSION} times the "
                               f"{data_length} {compression} bytes it stores: a corrupt size field")


class Rosbag1Writer(Writer):
    """rosbags' ROS 1 Writer with rosbag's bag-header record (see the module notes)."""

    def open(self) -> None:
        try:
            self.bio = self.path.open("xb")
        except FileExistsError:
            from rosbags.rosbag1 import WriterError

            raise WriterError(f"{self.path} exists already, not overwriting.") from None
        self.bio.write(BAG_MAGIC + file_header_record(0, 0, 0))

    def close(self) -> None:
        super().close()  # writes the index, then its own 4096-byte header record over ours
        with open(self.path, "r+b") as f:
            f.seek(len(BAG_MAGIC))
            (size,) = struct.unpack("<I", f.read(4))
            fields = parse_header_fields(f.read(size))
            record = file_header_record(struct.unpack("<Q", fields["index_pos"])[0],
                                        struct.unpack("<I", fields["conn_count"])[0],
                                        struct.unpack("<I", fields["chunk_count"])[0])
            f.seek(len(BAG_MAGIC))
            f.write(record)
