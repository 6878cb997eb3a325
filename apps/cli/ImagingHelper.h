// ImagingHelper: how `facet` runs the two commands that draw pictures.
//
// `facet render` and `facet bench` (its scatter plot) draw through
// OpenImageIO, whose shared library loads some 250 others; mapping them cost
// every `facet` process ~0.35 s before main(), for `facet eval` as much as
// for `facet render`. So the command line is built twice from the same
// sources: `facet` without the two picture commands, and `facet-imaging`,
// the whole command line linked with OpenImageIO, installed beside it.
// `facet render ...` and `facet bench ...` execute `facet-imaging render
// ...` with the same arguments, the way git runs its helper programs.
//
// The helper is code Facet runs, so it is trusted as the cache is
// (CacheFiles.h): it must be a regular file owned by root or the current
// user and writable by nobody else, in a directory with the same owners and
// rights; it is opened once, checked through that descriptor and executed
// through it (fexecve), so what was checked is what runs.
#pragma once

namespace facet {

// Replaces this process with facet-imaging running argv[1..]; returns only on
// failure, after printing why (naming the helper's path), with exit code 1.
int runImagingHelper(char** argv);

}  // namespace facet
