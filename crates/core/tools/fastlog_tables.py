#!/usr/bin/env python3
"""Tables and polynomial of crates/core/src/fastlog.rs (mpmath, 256-bit).

Usage: fastlog_tables.py [N=128] [DEG=5] > out.rs; prints the r range and the
polynomial's relative error on stderr. Takes about 20 s."""
import mpmath as mp, struct, sys
mp.mp.prec = 256
N = int(sys.argv[1]) if len(sys.argv) > 1 else 128
DEG = int(sys.argv[2]) if len(sys.argv) > 2 else 5
BITS = {128: 7, 256: 8, 64: 6}[N]
OFF = 0x3FE6A00000000000  # mantissa bits below the index are zero: 1.0 starts an interval
def f2b(x): return struct.unpack('<Q', struct.pack('<d', x))[0]
def b2f(b): return struct.unpack('<d', struct.pack('<Q', b))[0]
SH = 52 - BITS
invc, logc = [], []
rmin, rmax = 0, 0
for i in range(N):
    lo = b2f(OFF + (i << SH)); hi = b2f(OFF + ((i + 1) << SH))
    if lo == 1.0:
        ic = 1.0; lc = 0.0
    else:
        cen = mp.mpf(lo + hi) / 2
        best = None
        for j in range(0, 4000):
            for sgn in (1, -1):
                cand = float(1 / cen * (1 + sgn * j * mp.mpf(2) ** -36))
                l = -mp.log(mp.mpf(cand))
                d = float(l)
                err = abs((l - d) / mp.mpf(2) ** (mp.floor(mp.log(abs(l), 2)) - 52))
                if best is None or err < best[0]:
                    best = (err, cand, d)
            if best[0] < 2 ** -12:
                break
        _, ic, lc = best
    invc.append(ic); logc.append(lc)
    rmin = min(rmin, float(mp.mpf(lo) * ic - 1)); rmax = max(rmax, float(mp.mpf(hi) * ic - 1))
print("r range", rmin, rmax, mp.log(-rmin, 2), mp.log(rmax, 2), file=sys.stderr)
# Polynomial: log1p(r) = r + r^2 P(r), P degree DEG, minimax of |r^2 dP| / |log1p(r)| by Lawson.
a, b = mp.mpf(rmin), mp.mpf(rmax)
M = 400
pts = [(a + b) / 2 + (b - a) / 2 * mp.cos(mp.pi * (k + 0.5) / M) for k in range(M)]
target = [(mp.log1p(r) - r) / r ** 2 for r in pts]
wt = [abs(r ** 2 / mp.log1p(r)) for r in pts]
lw = [mp.mpf(1)] * M
for it in range(60):
    A = mp.matrix(M, DEG + 1); y = mp.matrix(M, 1)
    for k, r in enumerate(pts):
        s = mp.sqrt(lw[k]) * wt[k]
        for j in range(DEG + 1):
            A[k, j] = s * r ** j
        y[k] = s * target[k]
    coef = mp.lu_solve(A.T * A, A.T * y)
    errs = [abs(wt[k] * (sum(coef[j] * pts[k] ** j for j in range(DEG + 1)) - target[k])) for k in range(M)]
    tot = sum(lw[k] * errs[k] for k in range(M))
    lw = [lw[k] * errs[k] / tot for k in range(M)]
    lw = [max(w, mp.mpf(10) ** -30) for w in lw]
cd = [float(c) for c in coef]
errs = [abs(wt[k] * (sum(mp.mpf(cd[j]) * pts[k] ** j for j in range(DEG + 1)) - target[k])) for k in range(M)]
print("max rel err", float(max(errs)), float(mp.log(max(errs), 2)), file=sys.stderr)
print("// coefficients:", [c.hex() for c in cd])
for name, tab in (("INVC", invc), ("LOGC", logc)):
    print(f"const {name}: [f64; {N}] = [")
    for v in tab:
        print(f"    f64::from_bits(0x{f2b(v):016X}),")
    print("];")
for j, c in enumerate(cd):
    print(f"const A{j}: f64 = f64::from_bits(0x{f2b(c):016X}); // {c!r}")
