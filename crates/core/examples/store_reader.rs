//! Reading the store: memory map or positioned reads. The three ways the
//! library reads a store, each run twice over the same kernels: once on
//! the store's memory map (as the library reads it), once with `pread` into
//! a block the reader owns (one reused buffer a thread, `BLOCK_MB`
//! megabytes), with the page cache warm.
//!
//! - **reconstruction**: one pass over every row, `mean + w . z` of one
//!   latent point ([`brdf_atlas_core::simd::dot::rows`], the kernel of
//!   `Blend::table`);
//! - **exact albedo pass**: the dense albedo rule's rows (all channels,
//!   measured rows only) gathered in blocks of 256 and multiplied by the
//!   weights of `POINTS` latent points ([`brdf_atlas_core::dense::product::matmul`],
//!   the kernel of `Atlas::exact_albedos`);
//! - **Gram matrix**: `Z^T Z` over blocks of 512 rows laid out
//!   material-major ([`brdf_atlas_core::dense::gram32::syrk_lower_add_f32`],
//!   the kernel of `Store::gram` and of the fit's store pass).
//!
//! Each timed map run maps the store afresh (a host that opens a model pays
//! the page faults once); the library's own entry points (`Blend::table`,
//! `Atlas::exact_albedos`, `Store::gram`) are timed too, on a map of
//! their own, to show the prototypes do the same work.
//!
//! ```sh
//! cargo run --release -p brdf-atlas-core --example store_reader -- MODEL [RUNS] [BLOCK_MB] [POINTS]
//! ```

use std::cell::RefCell;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::time::Instant;

use brdf_atlas_core::dense::gram32::syrk_lower_add_f32;
use brdf_atlas_core::dense::product::matmul;
use brdf_atlas_core::simd::{dot, fastexp};
use brdf_atlas_core::{BlendRule, Model, NoProgress, Rows, Store, TransformKind};
use rayon::prelude::*;

/// Rows of the Gram kernel's blocks (the store's `BLOCK_ROWS`).
const GRAM_ROWS: usize = 512;
/// Rule rows gathered a block (the exact pass's block).
const RULE_BLOCK: usize = 256;

/// Where the rows come from.
enum Reader<'a> {
    /// The store's map, read `window` rows a task (as the pread reader).
    Map(&'a Store, usize),
    /// `pread` of the store file into a buffer of `window` rows a thread.
    Pread { file: File, z: u64, window: usize },
}

/// A thread's block: rows `start .. start + len` of `Z`, f32.
struct Window {
    start: usize,
    len: usize,
    buf: Vec<f32>,
}

thread_local! {
    static WINDOW: RefCell<Window> = const { RefCell::new(Window { start: 0, len: 0, buf: Vec::new() }) };
}

impl Reader<'_> {
    /// Run `f` on rows `r0 .. r1` of `Z` (f32, `n` a row), `r1 - r0` at
    /// most a window.
    fn with_rows<R>(
        &self,
        n: usize,
        rows: usize,
        r0: usize,
        r1: usize,
        f: impl FnOnce(&[f32]) -> R,
    ) -> R {
        match self {
            Reader::Map(store, _) => match store.z() {
                Rows::F32(z) => f(&z[r0 * n..r1 * n]),
                Rows::F64(_) => panic!("an f32 store, please"),
            },
            Reader::Pread { file, z, window } => WINDOW.with_borrow_mut(|w| {
                if r0 < w.start || r1 > w.start + w.len {
                    let len = (*window).min(rows - r0).max(r1 - r0);
                    w.buf.resize(len * n, 0.0);
                    file.read_exact_at(
                        bytemuck::cast_slice_mut(&mut w.buf[..len * n]),
                        z + (r0 * n * 4) as u64,
                    )
                    .expect("read the store");
                    (w.start, w.len) = (r0, len);
                }
                let o = r0 - w.start;
                f(&w.buf[o * n..(r1 - w.start) * n])
            }),
        }
    }

    fn window(&self) -> usize {
        match self {
            Reader::Map(_, window) => *window,
            Reader::Pread { window, .. } => *window,
        }
    }
}

/// Reconstruction: `mean + w . z` of every row; returns a checksum.
fn reconstruct(reader: &Reader, store: &Store, w: &[f64]) -> f64 {
    let (n, rows, mean) = (store.n(), store.rows(), store.mean());
    let step = reader.window();
    let mut out = vec![0.0f64; rows];
    out.par_chunks_mut(step).enumerate().for_each(|(k, out)| {
        let r0 = k * step;
        reader.with_rows(n, rows, r0, r0 + out.len(), |z| {
            dot::rows(w, z, &mean[r0..], out)
        })
    });
    out.iter().sum()
}

/// The exact albedo pass's reads and products at `m` points (weights `a`,
/// `n x m`), over `rule` rows with weights `wt`; returns the 3 x m sums.
fn exact(
    reader: &Reader,
    store: &Store,
    rule: &[(usize, u8, f64)],
    a: &[f64],
    m: usize,
    exp: bool,
) -> Vec<f64> {
    let (n, rows, mean) = (store.n(), store.rows(), store.mean());
    rule.par_chunks(RULE_BLOCK)
        .fold(
            || {
                (
                    vec![0.0f64; 3 * m],
                    vec![0.0f64; RULE_BLOCK * n],
                    vec![0.0f64; RULE_BLOCK * m],
                )
            },
            |(mut acc, mut z64, mut t64), block| {
                let len = block.len();
                for (k, &(row, _, _)) in block.iter().enumerate() {
                    reader.with_rows(n, rows, row, row + 1, |z| {
                        for (o, v) in z64[k * n..(k + 1) * n].iter_mut().zip(z) {
                            *o = *v as f64;
                        }
                    });
                }
                matmul(&mut t64[..m * len], a, &z64[..n * len], n);
                for (k, &(row, c, wt)) in block.iter().enumerate() {
                    let (mu, acc) = (mean[row], &mut acc[c as usize * m..(c as usize + 1) * m]);
                    let t = &t64[k * m..(k + 1) * m];
                    if exp {
                        for (o, t) in acc.iter_mut().zip(t) {
                            *o += wt * (fastexp::exp(mu + t) - 1.0).max(0.0);
                        }
                    } else {
                        for (o, t) in acc.iter_mut().zip(t) {
                            *o += wt * (mu + t).max(0.0);
                        }
                    }
                }
                (acc, z64, t64)
            },
        )
        .map(|(acc, _, _)| acc)
        .reduce(
            || vec![0.0; 3 * m],
            |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
        )
}

/// `Z^T Z` (lower triangle) over blocks of [`GRAM_ROWS`] rows.
fn gram(reader: &Reader, store: &Store) -> f64 {
    let (n, rows) = (store.n(), store.rows());
    let step = reader.window() / GRAM_ROWS * GRAM_ROWS;
    let windows = rows.div_ceil(step);
    let y = (0..windows)
        .into_par_iter()
        .fold(
            || (vec![0.0f64; n * n], vec![0.0f32; GRAM_ROWS * n]),
            |(mut acc, mut mm), k| {
                let (w0, w1) = (k * step, ((k + 1) * step).min(rows));
                for b0 in (w0..w1).step_by(GRAM_ROWS) {
                    let b1 = (b0 + GRAM_ROWS).min(w1);
                    let count = b1 - b0;
                    reader.with_rows(n, rows, b0, b1, |z| {
                        for (r, row) in z.chunks_exact(n).enumerate() {
                            for (i, v) in row.iter().enumerate() {
                                mm[i * count + r] = *v;
                            }
                        }
                    });
                    syrk_lower_add_f32(&mm[..count * n], count, &mut acc);
                }
                (acc, mm)
            },
        )
        .map(|(acc, _)| acc)
        .reduce(
            || vec![0.0; n * n],
            |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
        );
    y.iter().sum()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median seconds of `runs` runs of `f`, and its last answer.
fn time(runs: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
    let (mut t, mut last) = (Vec::new(), 0.0);
    for _ in 0..runs {
        let s = Instant::now();
        last = std::hint::black_box(f());
        t.push(s.elapsed().as_secs_f64());
    }
    (median(t), last)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: store_reader MODEL [RUNS] [BLOCK_MB] [POINTS]")?;
    let runs: usize = args.next().map_or(Ok(5), |s| s.parse())?;
    let block_mb: f64 = args.next().map_or(Ok(4.0), |s| s.parse())?;
    let m: usize = args.next().map_or(Ok(64), |s| s.parse())?;
    let model = brdf_atlas_core::Atlas::new(Model::open(&path)?);
    let store = model.store();
    let (n, rows) = (store.n(), store.rows());
    let z = store.len_bytes() - (rows * n * 4) as u64;
    let window = (block_mb * (1 << 20) as f64) as usize / (4 * n);
    let pread = || -> std::io::Result<Reader<'static>> {
        Ok(Reader::Pread {
            file: File::open(store.path())?,
            z,
            window,
        })
    };
    println!(
        "{path}: {n} materials, {rows} rows, {:.2} GB; {runs} runs, pread blocks of {block_mb} MB ({window} rows), {} threads",
        store.len_bytes() as f64 / 1e9,
        rayon::current_num_threads()
    );
    // Warm the page cache.
    let _ = std::hint::black_box(store.checksum());

    // The points: a grid over the latent points' box.
    let lat = model.latent();
    let (lo, hi) = (0..2).fold(([f64::MAX; 2], [f64::MIN; 2]), |(mut lo, mut hi), c| {
        for i in 0..lat.nrows() {
            lo[c] = lo[c].min(lat[(i, c)]);
            hi[c] = hi[c].max(lat[(i, c)]);
        }
        (lo, hi)
    });
    let side = (m as f64).sqrt().ceil() as usize;
    let points: Vec<[f64; 2]> = (0..m)
        .map(|k| {
            let (i, j) = ((k % side) as f64 + 0.5, (k / side) as f64 + 0.5);
            let s = side as f64;
            [
                lo[0] + (hi[0] - lo[0]) * i / s,
                lo[1] + (hi[1] - lo[1]) * j / s,
            ]
        })
        .collect();
    let blends: Vec<Vec<f64>> = points
        .iter()
        .map(|p| {
            model
                .at(p, brdf_atlas_core::BlendRule::Gp)
                .map(|b| b.gp_weights().to_vec())
        })
        .collect::<Result<_, _>>()?;
    let a: Vec<f64> = (0..n)
        .flat_map(|t| blends.iter().map(move |w| w[t]))
        .collect();
    let w = &blends[m / 2];
    let bins = store.dims().bins();
    let quad = model.albedo_rule();
    let unmeasured = store.unmeasured();
    let rule: Vec<(usize, u8, f64)> = (0..3)
        .flat_map(|c| {
            quad.bins()
                .iter()
                .zip(quad.weights())
                .map(move |(&b, &wt)| (c * bins + b as usize, c as u8, wt))
        })
        .filter(|&(row, _, _)| unmeasured[row] == 0)
        .collect();
    let exp = store.transform() != TransformKind::Raw;
    println!("exact pass: {m} points, {} rule rows", rule.len());

    let fresh = || Store::open(store.path()).expect("map the store");
    type Pattern<'a> = (&'a str, Box<dyn Fn(&Reader) -> f64 + 'a>);
    let patterns: Vec<Pattern> = vec![
        ("reconstruction", Box::new(|r| reconstruct(r, store, w))),
        (
            "exact albedo pass",
            Box::new(|r| exact(r, store, &rule, &a, m, exp).iter().sum()),
        ),
        ("Gram matrix", Box::new(|r| gram(r, store))),
    ];
    for (name, run) in &patterns {
        // Alternate the readers so a drift in the machine's load hits both.
        let (mut tm, mut tp, mut tw) = (Vec::new(), Vec::new(), Vec::new());
        let (mut am, mut ap) = (0.0, 0.0);
        for _ in 0..runs {
            let map = fresh();
            let s = Instant::now();
            am = std::hint::black_box(run(&Reader::Map(&map, window)));
            tm.push(s.elapsed().as_secs_f64());
            // The same map again: its pages are now mapped.
            let s = Instant::now();
            std::hint::black_box(run(&Reader::Map(&map, window)));
            tw.push(s.elapsed().as_secs_f64());
            let reader = pread()?;
            let s = Instant::now();
            ap = std::hint::black_box(run(&reader));
            tp.push(s.elapsed().as_secs_f64());
        }
        assert_eq!(
            am.to_bits(),
            ap.to_bits(),
            "{name}: both readers give the same sums"
        );
        let (m0, m1, p) = (median(tm), median(tw), median(tp));
        println!(
            "{name:<18} map {m0:7.3} s (mapped again {m1:7.3} s)  pread {p:7.3} s  pread/map {:.3} (/mapped again {:.3})",
            p / m0,
            p / m1
        );
    }
    // The library's own entry points, on their own map, for scale.
    let m2 = brdf_atlas_core::Atlas::new(Model::open(&path)?);
    let (t, _) = time(runs, || {
        m2.at(&points[m / 2], brdf_atlas_core::BlendRule::Gp)
            .and_then(|b| b.table())
            .map(|t| t.raw()[0])
            .unwrap_or(0.0)
    });
    println!("library: Blend::table {t:.3} s (the same map every run)");
    let (t, _) = time(runs, || {
        m2.exact_albedos(
            &points,
            brdf_atlas_core::AlbedoRequest::new().rule(BlendRule::Gp),
        )
        .map(|v| v[0][0])
        .unwrap_or(0.0)
    });
    println!("library: Atlas::exact_albedos(gp) {t:.3} s");
    let (t, _) = time(runs, || m2.store().gram(&NoProgress)[(0, 0)]);
    println!("library: Store::gram {t:.3} s");
    Ok(())
}
