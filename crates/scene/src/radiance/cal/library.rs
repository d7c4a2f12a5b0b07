//! Radiance's standard function files, written out here so that a scene needs no Radiance
//! installation: the definitions every function sees (`rayinit.cal`, as documented in its
//! header and Ward's `ray(1)` manual) and the luminaire coordinates of `source.cal`, which
//! `ies2rad`'s output names. Each is the same formula as Radiance's, in ircache's own text;
//! Radiance's noise functions and the texture-only names are not among them.

/// The global definitions (`rayinit.cal`).
pub const RAYINIT: &str = "
{ the modifier's real arguments }
AC = arg(0);
A1 = arg(1); A2 = arg(2); A3 = arg(3); A4 = arg(4); A5 = arg(5);
A6 = arg(6); A7 = arg(7); A8 = arg(8); A9 = arg(9); A10 = arg(10);

{ vectors as functions of their index }
D(i) = select(i, Dx, Dy, Dz);
N(i) = select(i, Nx, Ny, Nz);
P(i) = select(i, Px, Py, Pz);

{ library functions made safe at their domain's edges }
bound(a, x, b) : if(a - x, a, if(x - b, b, x));
Acos(x) : acos(bound(-1, x, 1));
Asin(x) : asin(bound(-1, x, 1));
Atan2(y, x) : if(x*x + y*y, atan2(y, x), 0);
Exp(x) : if(-x - 100, 0, exp(x));
Sqrt(x) : if(x, sqrt(x), 0);

PI : 3.14159265358979323846;
DEGREE : PI/180;
FTINY : 1e-7;

{ logic on signs: positive is true }
and(a, b) : if(a, b, a);
or(a, b) : if(a, a, b);
not(a) : if(a, -1, 1);
xor(a, b) : if(a, not(b), b);

abs(x) : if(x, x, -x);
sgn(x) : if(x, 1, if(-x, -1, 0));
sq(x) : x*x;
inside(a, x, b) : and(x - a, b - x);
frac(x) : x - floor(x);
mod(n, d) : n - floor(n/d)*d;
tri(n, d) : abs(d - mod(n - d, 2*d));
linterp(t, p0, p1) : (1 - t)*p0 + t*p1;

noop(v) : v;
clip(v) : bound(0, v, 1);
noneg(v) : if(v, v, 0);
red(r, g, b) : if(r, r, 0);
green(r, g, b) : if(g, g, 0);
blue(r, g, b) : if(b, b, 0);
grey(r, g, b) : noneg(.265074126*r + .670114631*g + .064811243*b);
clip_r(r, g, b) : bound(0, r, 1);
clip_g(r, g, b) : bound(0, g, 1);
clip_b(r, g, b) : bound(0, b, 1);
clipgrey(r, g, b) : min(grey(r, g, b), 1);

dot(v1, v2) : v1(1)*v2(1) + v1(2)*v2(2) + v1(3)*v2(3);
cross(i, v1, v2) : select(i, v1(2)*v2(3) - v1(3)*v2(2),
                             v1(3)*v2(1) - v1(1)*v2(3),
                             v1(1)*v2(2) - v1(2)*v2(1));

fade(near_val, far_val, dist) : far_val +
        if(16 - dist, (near_val - far_val)/(1 + dist*dist), 0);

hermite(p0, p1, r0, r1, t) : p0*((2*t - 3)*t*t + 1) + p1*(-2*t + 3)*t*t
        + r0*(((t - 2)*t + 1)*t) + r1*((t - 1)*t*t);
bezier(p1, p2, p3, p4, t) : p1*(1 + t*(-3 + t*(3 - t))) + p2*3*t*(1 + t*(-2 + t))
        + p3*3*t*t*(1 - t) + p4*t*t*t;
bspline(pp, p0, p1, pn, t) : pp*(1/6 + t*(-.5 + t*(.5 - 1/6*t))) + p0*(2/3 + t*t*(-1 + .5*t))
        + p1*(1/6 + t*(.5 + t*(.5 - .5*t))) + pn*(1/6*t*t*t);

{ a normal deviate from a uniform one (rational approximation) }
unif2norm.tail(t) : t - (2.515517 + t*(.802853 + t*.010328))
        / (1 + t*(1.432788 + t*(.189269 + t*.001308)));
unif2norm.half(p) : unif2norm.tail(sqrt(-2*log(p)));
unif2norm(p) : if(.5 - p, -unif2norm.half(p), unif2norm.half(1 - p));
nrand(x) = unif2norm(rand(x));

{ local (u, v) coordinates on planar surfaces }
uv.crosslen = Nx*Nx + Ny*Ny;
U = if(uv.crosslen - FTINY, (Py*Nx - Px*Ny)/uv.crosslen, Px);
V = if(uv.crosslen - FTINY, Pz - Nz*(Px*Nx + Py*Ny)/uv.crosslen, Py);
";

/// Luminaire coordinates and the corrections of `ies2rad`'s emitting shapes (`source.cal`):
/// angles in degrees, θ from the −z axis (the nadir), φ from +x towards +y, of the direction the
/// light leaves in; `flatcorr`, `boxcorr` and `cylcorr` divide by the shape's projected area
/// (box and cylinder dimensions in metres as `A2…A4`), `corr` applies the multiplier `A1`.
pub const SOURCE_CAL: &str = "
boxprojection = abs(Dx)*A3*A4 + abs(Dy)*A2*A4 + abs(Dz)*A2*A3;
lboxprojection = (noneg(abs(Px - Dx*Ts) - A2/2)*A3*A4
        + noneg(abs(Py - Dy*Ts) - A3/2)*A2*A4
        + noneg(abs(Pz - Dz*Ts) - A4/2)*A2*A3) / Ts;
cylprojection = A2*A3*sqrt(1 - Dz*Dz) + PI/4*A2*A2*abs(Dz);

flatcorr(v) = corr(v) / Rdot;
corr(v) = if(AC - .5, A1*v, v);
boxcorr(v) = A1*v / boxprojection;
lboxcorr(v) = A1*v / lboxprojection;
cylcorr(v) = A1*v / cylprojection;

src_theta = Acos(Dz) / DEGREE;
src_phi = mod(Atan2(-Dy, -Dx) / DEGREE, 360);
src_phi2 = tri(src_phi, 180);
src_phi4 = tri(src_phi, 90);

srcB_vert = atan2(-Dx, Dz) / DEGREE;
srcB_horiz = atan2(Dy, Dz) / DEGREE;
srcB_vert2 = abs(srcB_vert);
srcB_horiz2 = abs(srcB_horiz);
";

/// The text of a standard function file ircache carries, by its file name.
#[must_use]
pub fn standard_file(name: &str) -> Option<&'static str> {
    match name {
        "source.cal" | "source" => Some(SOURCE_CAL),
        _ => None,
    }
}
