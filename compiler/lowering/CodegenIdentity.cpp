// CodegenIdentity: the code generator's part of the kernel cache key (see
// CodegenIdentity.h).
#include "CodegenIdentity.h"

#include "TermEmitters.h"

#include <llvm/ADT/StringExtras.h>
#include <llvm/Config/llvm-config.h>
#include <llvm/Support/SHA256.h>

#include <fmt/format.h>

#include "CodegenSourceDigest.inc"  // kCodegenSourceDigest, kCodegenSourceList

namespace facet {

const char* codegenSourceDigest() { return kCodegenSourceDigest; }
const char* codegenSourceList() { return kCodegenSourceList; }

std::vector<EmbeddedTable> embeddedTables(const CheckedMaterial& material) {
    std::vector<EmbeddedTable> all;
    if (material.combinesLobes()) {  // every lobe's (the layers' tables follow from the material's text)
        for (size_t l = 0; l < material.lobes.size(); ++l)
            for (const EmbeddedTable& t : embeddedTables(lobeView(material, int(l)))) all.push_back(t);
        return all;
    }
    for (const ModelUse* use : {&material.singleLobe().ndf, &material.singleLobe().masking, &material.singleLobe().fresnel, &material.singleLobe().diffuse, &material.singleLobe().energy})
        if (const TermEmitterEntry* e = use->model ? findTermEmitterEntry(*use->model) : nullptr; e && e->tables)
            for (const EmbeddedTable& t : e->tables(material)) all.push_back(t);
    return all;
}

std::string codegenIdentity(std::string_view sourceDigest, const std::vector<EmbeddedTable>& tables) {
    llvm::SHA256 hash;
    for (const EmbeddedTable& t : tables) {
        // name, size, bytes: a renamed or resized table changes the digest too.
        hash.update(t.name);
        hash.update(llvm::StringRef("\0", 1));
        hash.update(fmt::format("{}", t.bytes));
        hash.update(llvm::ArrayRef<uint8_t>(static_cast<const uint8_t*>(t.data), t.bytes));
    }
    std::array<uint8_t, 32> digest = hash.final();
    return fmt::format("codegen v{}; sources {}; tables {}; llvm {}", kCodegenVersion, sourceDigest,
                       llvm::toHex(digest, true), LLVM_VERSION_STRING);
}

std::string codegenIdentity(const CheckedMaterial& material) {
    return codegenIdentity(kCodegenSourceDigest, embeddedTables(material));
}

}  // namespace facet
