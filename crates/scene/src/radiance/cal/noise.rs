//! Radiance's noise functions (`src/rt/noise3.c`), which its function files call like the
//! library's: `noise3(x, y, z)`, Perlin's improved noise (2002); `noise3x`, `noise3y`,
//! `noise3z`, its partial derivatives by Radiance's backward difference of 0.0005; and
//! `fnoise3(x, y, z)`, the fractal noise of a midpoint subdivision with a hashed displacement.
//! The same values as Radiance's, bit for bit where the arithmetic allows (tested through
//! `rtrace`).

/// Radiance's `EPSILON` in `noise3.c`: the difference step and the fractal's finest scale.
const EPSILON: f64 = 0.0005;

/// Perlin's permutation.
const PERMUTATION: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

fn p(i: i32) -> i32 {
    i32::from(PERMUTATION[(i & 0xff) as usize])
}

fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn lerp(t: f64, a: f64, b: f64) -> f64 {
    a + t * (b - a)
}

fn grad(hash: i32, x: f64, y: f64, z: f64) -> f64 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// Perlin's improved noise at (x, y, z), as `noise3.c`'s `perlin_noise`.
#[must_use]
pub fn perlin(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    // The unit cube holding the point (C's truncation, one less below zero).
    let cell = |v: f64| (v as i32).wrapping_sub(i32::from(v < 0.0));
    let (cx, cy, cz) = (cell(x), cell(y), cell(z));
    x -= f64::from(cx);
    y -= f64::from(cy);
    z -= f64::from(cz);
    let (cx, cy, cz) = (cx & 0xff, cy & 0xff, cz & 0xff);
    let (u, v, w) = (fade(x), fade(y), fade(z));
    let a = p(cx) + cy;
    let (aa, ab) = (p(a) + cz, p(a + 1) + cz);
    let b = p(cx + 1) + cy;
    let (ba, bb) = (p(b) + cz, p(b + 1) + cz);
    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(p(aa), x, y, z), grad(p(ba), x - 1.0, y, z)),
            lerp(
                u,
                grad(p(ab), x, y - 1.0, z),
                grad(p(bb), x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(p(aa + 1), x, y, z - 1.0),
                grad(p(ba + 1), x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(p(ab + 1), x, y - 1.0, z - 1.0),
                grad(p(bb + 1), x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

/// `noise3x`, `noise3y`, `noise3z` (`axis` 0, 1, 2): Radiance's backward difference of the
/// noise along one axis.
#[must_use]
pub fn partial(x: f64, y: f64, z: f64, axis: usize) -> f64 {
    let f = perlin(x, y, z);
    let back = match axis {
        0 => perlin(x - EPSILON, y, z),
        1 => perlin(x, y - EPSILON, z),
        _ => perlin(x, y, z - EPSILON),
    };
    (f - back) / EPSILON
}

/// `noise3.c`'s `frand`: a hash of an integer to [−1, 1) (C's `long` arithmetic, wrapping, as
/// everywhere here: points beyond ±4.6·10¹⁵ wrap instead of overflowing).
fn frand(s: i64) -> f64 {
    let s = (s << 13) ^ s;
    let t = s
        .wrapping_mul(s.wrapping_mul(s).wrapping_mul(15731).wrapping_add(789_221))
        .wrapping_add(1_376_312_589)
        & 0x7fff_ffff;
    1.0 - t as f64 / 1_073_741_824.0
}

fn frand3(x: i64, y: i64, z: i64) -> f64 {
    frand(
        17i64
            .wrapping_mul(x)
            .wrapping_add(23i64.wrapping_mul(y))
            .wrapping_add(29i64.wrapping_mul(z)),
    )
}

/// `fnoise3`: fractal noise by midpoint subdivision of the unit cube holding the point down to
/// 0.0005, each new point displaced by a hash scaled to its level (`noise3.c` line by line).
#[must_use]
pub fn fractal(x: [f64; 3]) -> f64 {
    let mut s: i64 = (1.0 / EPSILON) as i64;
    let t: [i64; 3] = x.map(|v| (s as f64 * v) as i64);
    let mut beg: [i64; 3] = x.map(|v| (s as f64 * v.floor()) as i64);
    let mut fval = [0.0f64; 8];
    let mut v = [0i64; 3];
    for (j, f) in fval.iter_mut().enumerate() {
        for i in 0..3 {
            v[i] = beg[i].wrapping_add(if j & (1 << i) != 0 { s } else { 0 });
        }
        *f = frand3(v[0], v[1], v[2]);
    }
    loop {
        let mut fc = fval.iter().sum::<f64>() * 0.125;
        s >>= 1;
        if s == 0 {
            return fc;
        }
        let mut branch = 0usize;
        for i in 0..3 {
            v[i] = beg[i].wrapping_add(s);
            if t[i] > v[i] {
                branch |= 1 << i;
            }
        }
        fc += s as f64 * EPSILON * frand3(v[0], v[1], v[2]);
        fval[!branch & 7] = fc;
        for i in 0..3 {
            // Faces.
            v[i] = if branch & (1 << i) != 0 {
                v[i].wrapping_add(s)
            } else {
                v[i].wrapping_sub(s)
            };
            let mut sum = 0.0;
            for (j, f) in fval.iter().enumerate() {
                if !(j ^ branch) & (1 << i) != 0 {
                    sum += f;
                }
            }
            fval[!(branch ^ (1 << i)) & 7] =
                0.25 * sum + s as f64 * EPSILON * frand3(v[0], v[1], v[2]);
            v[i] = beg[i].wrapping_add(s);
        }
        for i in 0..3 {
            // Edges.
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            for a in [j, k] {
                v[a] = if branch & (1 << a) != 0 {
                    v[a].wrapping_add(s)
                } else {
                    v[a].wrapping_sub(s)
                };
            }
            let f = fval[branch & !(1 << i)] + fval[branch | (1 << i)];
            fval[branch ^ (1 << i)] = 0.5 * f + s as f64 * EPSILON * frand3(v[0], v[1], v[2]);
            v[j] = beg[j].wrapping_add(s);
            v[k] = beg[k].wrapping_add(s);
        }
        for (i, b) in beg.iter_mut().enumerate() {
            if branch & (1 << i) != 0 {
                *b = b.wrapping_add(s);
            }
        }
    }
}
