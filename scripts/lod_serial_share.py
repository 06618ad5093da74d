#!/usr/bin/env python3
# The share of `conelod lod build`'s samples that run outside the threads' work (issue 27; docs/
# scale.md, "Threading"). Record a build at --threads 1 with a binary whose lod_dag.cpp has debug info
# (inline frames), e.g. a build folder configured with -DCMAKE_CXX_FLAGS=-g:
#   perf record -F 250 --call-graph dwarf,16384 -o lod.data build-g/conelod/conelod lod build IN.ply \
#        -o OUT.clod --threads 1 [--memory 128M]
#   scripts/lod_serial_share.py lod.data [N]
# A sample is the build's when a frame is BuildDag, BuildLodDagFromChunks, BuildLevels or
# StreamLevels; it is the threads' work when a frame is RunThreads, ParallelChunks, ParallelItems or
# SimplifyGroup (what runs inside conelod/parallel.h's pools); the others are serial. Prints the
# two shares and the N [12] most frequent innermost functions of the serial samples.
import collections
import re
import subprocess
import sys

data = sys.argv[1]
top = int(sys.argv[2]) if len(sys.argv) > 2 else 12
out = subprocess.run(['perf', 'script', '-i', data, '-F', 'comm,tid,ip,sym'], capture_output=True, text=True,
                     check=True).stdout
count = collections.Counter()
where = collections.Counter()
for sample in out.split('\n\n'):
    lines = [l.strip() for l in sample.strip().split('\n') if l.strip()]
    if len(lines) < 2:
        continue
    frames = [l.split(None, 1)[1] if len(l.split(None, 1)) > 1 else '' for l in lines[1:]]
    text = '\n'.join(frames)
    if not any(k in text for k in ('BuildLevels', 'StreamLevels', 'BuildDag', 'BuildLodDagFromChunks')):
        count['other'] += 1
        continue
    threads = any(k in text for k in ('RunThreads', 'ParallelChunks', 'ParallelItems', 'SimplifyGroup'))
    count['threads' if threads else 'serial'] += 1
    if not threads:
        names = []
        for f in frames:
            m = re.search(r'(?:conelod::(?:\(anonymous namespace\)::)?)?\b([A-Z]\w+) \(inlined\)|'
                          r'conelod::(?:\(anonymous namespace\)::)?([A-Z]\w+)', f)
            name = m and (m.group(1) or m.group(2))
            if name and (not names or names[-1] != name):
                names.append(name)
        where[' < '.join(names[:3])] += 1
build = count['threads'] + count['serial']
if build == 0:
    sys.exit('no sample of the LOD build in ' + data)
print('samples %d: outside the build (reading, writing) %d; the build %d: on the threads %.1f %%, serial %.1f %%' %
      (sum(count.values()), count['other'], build, 100.0 * count['threads'] / build, 100.0 * count['serial'] / build))
for k, v in where.most_common(top):
    print('  %5.1f %%  %s' % (100.0 * v / build, k))
