// CodegenIdentity: what the kernel cache key says about the code generator.
//
// A cached object may be reused only by a Facet whose code generation would
// produce the same object. That is settled by: a version constant, bumped
// by hand when the generated code's ABI or meaning changes; the SHA-256 of
// every source file that shapes the generated code (the front end,
// the model catalog and emitters, the lowering, the JIT's pipeline), taken
// at build time from their contents, so two builds of the same source agree
// and any edit changes it; the SHA-256 of every constant table the lowering
// embeds for the material (the models' emitters list theirs); and the LLVM
// version. The
// kernel cache adds the CPU and the material (runtime/KernelCache.h).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace facet {

struct CheckedMaterial;

// Bump when a cached object's ABI or meaning changes without a source change
// that the digest would catch.
constexpr int kCodegenVersion = 1;

// A constant table the lowering may embed in a module: its name and bytes.
struct EmbeddedTable {
    std::string name;
    const void* data = nullptr;
    size_t bytes = 0;
};

// The tables the kernel of `material` embeds (TermEmitterEntry::tables of
// its models' emitters).
std::vector<EmbeddedTable> embeddedTables(const CheckedMaterial& material);

// SHA-256 (hex) of the codegen sources, computed at build time
// (cmake/HashSources.cmake); codegenSourceList() names the files, relative
// to the source tree, in the order hashed.
const char* codegenSourceDigest();
const char* codegenSourceList();

// "codegen v<N>; sources <sha>; tables <sha>; llvm <version>".
std::string codegenIdentity(std::string_view sourceDigest, const std::vector<EmbeddedTable>& tables);
// The identity of this build's code generator for the kernel of `material`.
std::string codegenIdentity(const CheckedMaterial& material);

}  // namespace facet
