// SPDX-License-Identifier: MIT
// Small text outputs (summary.json, case.resolved.yaml, XDMF sidecars) written so that a reader
// never sees half a file: a run killed mid-write leaves the previous version or the new one.
#pragma once
#include <string>

namespace tessera {

// Writes text to path atomically (temporary file + rename); call it on one rank.
void write_file_atomically(const std::string& path, const std::string& text);

}  // namespace tessera
