"""Attributes a QEMU `-d in_asm,exec,nochain` trace to functions (see qemu-profile.sh).

usage: qemu-profile.py <elf> <trace.log> [top-N]

A translation block's size is read from its `IN:` listing; a block is known
by its host address (the `Trace` line's first field), which QEMU logs right
after translating it, so a block translated again with other flags (icount
splits blocks at I/O) is counted with its own size. The demo ends where
`qemu::profile` is first entered.
"""
import bisect
import collections
import re
import subprocess
import sys

HELPERS = ('memcpy', 'memcmp', 'memset', 'div')


def symbols(elf):
    out = subprocess.run(['llvm-nm', '-C', '-n', '-S', elf], capture_output=True,
                         text=True, check=True).stdout
    syms = []
    for line in out.splitlines():
        parts = line.split(None, 3)
        if len(parts) == 4 and parts[2] in 'tTwW':
            syms.append((int(parts[0], 16) & ~1, int(parts[1], 16), parts[3]))
    syms.sort()
    return syms


def readable(sym):
    """Rust's legacy mangling escapes, hashes and typenum spellings made short."""
    sym = re.sub(r'::h[0-9a-f]{16}$', '', sym)
    for code, text in (('$LT$', '<'), ('$GT$', '>'), ('$C$', ','), ('$u20$', ' '),
                       ('$RF$', '&'), ('..', '::')):
        sym = sym.replace(code, text)
    return re.sub(r'<typenum::.*?>(?=>)', '<..>', sym)


def main():
    elf, log = sys.argv[1], sys.argv[2]
    top = int(sys.argv[3]) if len(sys.argv) > 3 else 40
    syms = symbols(elf)
    starts = [s[0] for s in syms]
    cache = {}

    def name(pc):
        if pc not in cache:
            i = bisect.bisect_right(starts, pc) - 1
            if i >= 0 and pc < syms[i][0] + max(syms[i][1], 2):
                cache[pc] = readable(syms[i][2])
            else:
                cache[pc] = '?%x' % pc
        return cache[pc]

    profile = [s for s in syms if s[2].startswith('qemu::profile::')]
    lo, hi = (profile[0][0], profile[0][0] + profile[0][1]) if profile else (1, 0)
    size = {}
    pending, count = None, 0
    phase = 'demo'
    runs = {'demo': collections.Counter(), 'profile': collections.Counter()}
    callers = collections.Counter()
    prev = 0
    trace = re.compile(r'^Trace \d+: (0x[0-9a-f]+) \[[0-9a-f]+/([0-9a-f]+)/')
    with open(log, errors='replace') as f:
        for line in f:
            c = line[0]
            if c == 'T':
                m = trace.match(line)
                if not m:
                    continue
                host, pc = m.group(1), int(m.group(2), 16)
                if pending is not None:
                    if pending == pc:
                        size[host] = (pc, count)
                    pending = None
                if phase == 'demo' and lo <= pc < hi:
                    phase = 'profile'
                runs[phase][host] += 1
                if phase == 'demo':
                    callee = name(pc)
                    if any(h in callee for h in HELPERS) and name(prev) != callee:
                        callers[(callee, name(prev))] += 1
                prev = pc
            elif c == 'I' and line.startswith('IN:'):
                pending, count = None, 0
            elif c == '0' and line.startswith('0x'):
                if pending is None:
                    pending, count = int(line[2:10], 16), 0
                count += 1
    for phase, run in runs.items():
        per = collections.Counter()
        for host, n in run.items():
            pc, k = size.get(host, (0, 0))
            per[name(pc)] += n * k
        total = sum(per.values())
        print(f'== {phase}: {total} instructions')
        for fn, n in per.most_common(top):
            print(f'{n:11d} {100 * n / max(total, 1):5.1f}%  {fn[:120]}')
    print('== helper calls during the demo, by caller')
    for (callee, caller), n in callers.most_common(top):
        if not any(h in caller for h in HELPERS):
            print(f'{n:9d}  {callee[:40]} <- {caller[:90]}')


if __name__ == '__main__':
    main()
