#pragma once
// The heap policy of a long solver job: freed memory is kept for the next allocation instead of
// being returned to the system.
//
// A station's solve allocates and frees the same large arrays again and again (CHOLMOD's factors
// and workspaces, the PGD's update matrices, hundreds of MB each). glibc serves each from a fresh
// mmap and unmaps it on free, so every station faults in its memory page by page, and two station
// workers then queue on the process's memory-map lock. Measured on the flat plate at the case's
// scale with the PGD (`drom offline --set solver.kind=pgd --set mesh.element=hex27`, two workers,
// first two stations): 21 million page faults and 82 s of system time in 3 min 56 s; with this
// policy 2.1 million, 24 s, and 3 min 12 s, for a peak RSS of 8.5 GB instead of 6.8 GB.
namespace drom {

// From here on (process-wide): large blocks from the heap, not from mmap; one arena, so that a
// block one worker frees serves the next worker's request; no trimming of the heap's top. Call it
// first in main: a thread that has allocated before it keeps an arena of its own.
void keep_freed_memory();

}  // namespace drom
