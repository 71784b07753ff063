"""MAVLink FTP (FILE_TRANSFER_PROTOCOL), refused: the simulated vehicle has no files.

A request that names a file or directory is answered NAK FileNotFound, any other
request NAK UnknownCommand, so a client stops at once instead of timing out
(MAVProxy then fetches parameters with PARAM_REQUEST_LIST); ending or resetting
sessions is acknowledged. Replies (ACK, NAK) are never answered.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

OP_TERMINATE_SESSION, OP_RESET_SESSIONS = 1, 2
OP_ACK, OP_NAK = 128, 129
ERR_UNKNOWN_COMMAND, ERR_FILE_NOT_FOUND = 7, 10
# ListDirectory, OpenFileRO, CreateFile, RemoveFile, CreateDirectory, RemoveDirectory,
# OpenFileWO, TruncateFile, Rename, CalcFileCRC32, ListDirectoryWithTime.
PATH_OPS = frozenset({3, 4, 6, 8, 9, 10, 11, 12, 13, 14, 16})
_HEADER = struct.Struct("<HBBBBBBI")  # seq, session, opcode, size, req_opcode, burst, pad, offset
PAYLOAD_LEN = 251


class FtpService:
    """Answers FILE_TRANSFER_PROTOCOL requests on the server's encoder `m`."""

    def __init__(self, m: Any, sysid: int) -> None:
        self.m = m
        self.sysid = sysid
        self.messages: dict[str, Callable[[Any], None]] = {"FILE_TRANSFER_PROTOCOL": self._request}

    def tick(self, now: float) -> None:
        """Nothing runs between requests."""

    def _request(self, msg: Any) -> None:
        if msg.target_system not in (0, self.sysid):
            return
        raw = bytes(msg.payload)
        if len(raw) < _HEADER.size:
            return
        seq, session, opcode, *_ = _HEADER.unpack_from(raw)
        if opcode >= OP_ACK or opcode == 0:
            return  # a reply, or no operation: nothing to answer
        if opcode in (OP_TERMINATE_SESSION, OP_RESET_SESSIONS):
            reply, data = OP_ACK, b""
        else:
            error = ERR_FILE_NOT_FOUND if opcode in PATH_OPS else ERR_UNKNOWN_COMMAND
            reply, data = OP_NAK, bytes([error])
        header = _HEADER.pack((seq + 1) & 0xFFFF, session, reply, len(data), opcode, 0, 0, 0)
        payload = (header + data).ljust(PAYLOAD_LEN, b"\0")
        self.m.file_transfer_protocol_send(
            0, msg.get_srcSystem(), msg.get_srcComponent(), list(payload)
        )
