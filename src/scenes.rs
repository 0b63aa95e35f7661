//! The standard scenes, defined once for the host tests, the benches and the boards (feature `scenes`).
//!
//! `big`, `overdraw` and `small` are W1, W2 and W3 of the project's benchmark workloads (described in the README), exactly:
//! 320 x 240, flat colour per triangle, drawn in the order listed, depth cleared, `Less`. Their vertices are given on
//! pixel centres; wraster's centres are at `i + 0.5`, so `(x, y)` of the workloads becomes `(x + 0.5, y + 0.5)`.
//! `terrain` is the demo scene: a ground grid receding from `W_near = 10` to `W_far = 10000` with interpenetrating
//! boxes near and far, projected with f32 arithmetic only (IEEE operations, so the same bits on every target).

use embedded_graphics_core::pixelcolor::{Rgb565, RgbColor};

use crate::Vertex;

/// Frame width of every standard scene.
pub const WIDTH: u16 = 320;
/// Frame height of every standard scene.
pub const HEIGHT: u16 = 240;

/// One of the standard scenes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scene {
    /// W1: one triangle of about 32,000 pixels.
    Big,
    /// W2: 16 large triangles at mixed depths.
    Overdraw,
    /// W3: 2,000 triangles of 18 pixels in a 40 x 25 grid of quads.
    Small,
    /// The demo: ground grid and boxes, `W_near = 10`, `W_far = 10000`.
    Terrain,
}

/// A triangle of a scene.
pub type Tri = [Vertex<Rgb565>; 3];

const PALETTE: [Rgb565; 8] = [
    Rgb565::new(31, 0, 0),
    Rgb565::new(0, 63, 0),
    Rgb565::new(0, 0, 31),
    Rgb565::new(31, 63, 0),
    Rgb565::new(0, 63, 31),
    Rgb565::new(31, 0, 31),
    Rgb565::new(31, 40, 10),
    Rgb565::new(12, 30, 31),
];

/// W1 of workloads.md, (x, y, W).
pub const BIG: [[(f32, f32, f32); 3]; 1] = [[
    (10.0, 10.0, 10.0),
    (310.0, 40.0, 1000.0),
    (60.0, 230.0, 100.0),
]];

/// W2 of workloads.md (xorshift32, seed 2463534242), (x, y, W).
pub const OVERDRAW: [[(f32, f32, f32); 3]; 16] = [
    [
        (134.0, 136.0, 891.0),
        (96.0, 12.0, 696.0),
        (256.0, 17.0, 241.0),
    ],
    [
        (216.0, 232.0, 51.0),
        (193.0, 56.0, 916.0),
        (319.0, 151.0, 618.0),
    ],
    [
        (26.0, 185.0, 839.0),
        (141.0, 1.0, 638.0),
        (232.0, 231.0, 47.0),
    ],
    [
        (171.0, 0.0, 335.0),
        (245.0, 179.0, 908.0),
        (46.0, 131.0, 994.0),
    ],
    [
        (240.0, 125.0, 196.0),
        (72.0, 239.0, 374.0),
        (74.0, 37.0, 731.0),
    ],
    [
        (250.0, 239.0, 995.0),
        (41.0, 176.0, 257.0),
        (228.0, 52.0, 634.0),
    ],
    [
        (261.0, 87.0, 926.0),
        (215.0, 239.0, 891.0),
        (36.0, 129.0, 977.0),
    ],
    [(125.0, 9.0, 96.0), (64.0, 199.0, 239.0), (0.0, 62.0, 32.0)],
    [
        (170.0, 234.0, 117.0),
        (9.0, 162.0, 660.0),
        (172.0, 81.0, 938.0),
    ],
    [
        (55.0, 72.0, 347.0),
        (262.0, 46.0, 257.0),
        (154.0, 216.0, 597.0),
    ],
    [
        (22.0, 40.0, 197.0),
        (254.0, 66.0, 683.0),
        (135.0, 218.0, 37.0),
    ],
    [
        (186.0, 180.0, 837.0),
        (0.0, 156.0, 489.0),
        (94.0, 0.0, 742.0),
    ],
    [
        (202.0, 23.0, 753.0),
        (266.0, 212.0, 827.0),
        (89.0, 173.0, 514.0),
    ],
    [
        (170.0, 128.0, 896.0),
        (36.0, 218.0, 533.0),
        (26.0, 64.0, 656.0),
    ],
    [
        (231.0, 0.0, 937.0),
        (210.0, 203.0, 385.0),
        (0.0, 87.0, 615.0),
    ],
    [
        (0.0, 0.0, 484.0),
        (181.0, 42.0, 173.0),
        (53.0, 196.0, 602.0),
    ],
];

fn centred(t: &[(f32, f32, f32); 3], color: Rgb565) -> Tri {
    t.map(|(x, y, w)| Vertex::new(x + 0.5, y + 0.5, w, color))
}

impl Scene {
    /// Every scene, in a fixed order.
    pub const ALL: [Scene; 4] = [Scene::Big, Scene::Overdraw, Scene::Small, Scene::Terrain];

    /// The scene's name as the bench and demo lines print it.
    pub fn name(self) -> &'static str {
        match self {
            Scene::Big => "big",
            Scene::Overdraw => "overdraw",
            Scene::Small => "small",
            Scene::Terrain => "terrain",
        }
    }

    /// `(W_near, W_far)` the scene is drawn with. W1-W3 have W in [10, 1000]; they use `W_near = 1`, `W_far = 1000`.
    pub fn depth_range(self) -> (f32, f32) {
        match self {
            Scene::Terrain => (10.0, 10000.0),
            _ => (1.0, 1000.0),
        }
    }

    /// Number of triangles.
    pub fn len(self) -> usize {
        match self {
            Scene::Big => 1,
            Scene::Overdraw => 16,
            Scene::Small => 2000,
            Scene::Terrain => TERRAIN_TRIS,
        }
    }

    /// Never empty.
    pub fn is_empty(self) -> bool {
        false
    }

    /// Triangle `k` (`k < len()`), in drawing order.
    pub fn tri(self, k: usize) -> Tri {
        match self {
            Scene::Big => centred(&BIG[0], PALETTE[0]),
            Scene::Overdraw => centred(&OVERDRAW[k], PALETTE[k % 8]),
            Scene::Small => small(k),
            Scene::Terrain => terrain(k),
        }
    }

    /// The triangles in drawing order.
    pub fn tris(self) -> impl Iterator<Item = Tri> {
        (0..self.len()).map(move |k| self.tri(k))
    }
}

/// W3: quad (i, j), i < 40, j < 25, row-major; grid vertex (i, j) at x = 40 + 6i, y = 45 + 6j, W = 10 + 20i + 7j.
fn small(k: usize) -> Tri {
    let (quad, second) = (k / 2, k % 2 == 1);
    let (i, j) = ((quad % 40) as f32, (quad / 40) as f32);
    let g = |di: f32, dj: f32| {
        (
            40.0 + 6.0 * (i + di),
            45.0 + 6.0 * (j + dj),
            10.0 + 20.0 * (i + di) + 7.0 * (j + dj),
        )
    };
    let t = if second {
        [g(0.0, 0.0), g(1.0, 1.0), g(0.0, 1.0)]
    } else {
        [g(0.0, 0.0), g(1.0, 0.0), g(1.0, 1.0)]
    };
    centred(&t, PALETTE[(quad + quad / 40) % 8])
}

// Terrain: camera at the origin looking down +Z, focal length 160 px, principal point (160, 100), ground at Y = -15.
const COLS: usize = 16;
const ROWS: usize = 26;
const GROUND_TRIS: usize = COLS * ROWS * 2;
/// Boxes: (centre X, bottom Y, top Y, centre Z, half size).
const BOXES: [(f32, f32, f32, f32, f32); 6] = [
    (-14.0, -20.0, -2.0, 45.0, 6.0),
    (-7.0, -18.0, 1.0, 50.0, 5.0), // cuts into the first box and into the ground
    (18.0, -16.0, -6.0, 30.0, 3.0),
    (-700.0, -40.0, 600.0, 3000.0, 250.0),
    (-450.0, -30.0, 420.0, 3200.0, 220.0), // cuts into the box above
    (1500.0, -60.0, 2500.0, 8000.0, 500.0),
];
const TERRAIN_TRIS: usize = GROUND_TRIS + BOXES.len() * 12;

fn project(x: f32, y: f32, z: f32, color: Rgb565) -> Vertex<Rgb565> {
    Vertex::new(160.0 + 160.0 * x / z, 100.0 - 160.0 * y / z, z, color)
}

/// Ground row `k` depth: 10.5 * 1.3 ^ k, capped below the far plane.
fn row_z(k: usize) -> f32 {
    let mut z = 10.5f32;
    for _ in 0..k {
        z *= 1.3;
    }
    if z > 9990.0 {
        9990.0
    } else {
        z
    }
}

fn terrain(k: usize) -> Tri {
    if k < GROUND_TRIS {
        let (quad, second) = (k / 2, k % 2 == 1);
        let (a, r) = (quad % COLS, quad / COLS);
        let (z0, z1) = (row_z(r), row_z(r + 1));
        let s = |a: usize| -1.2 + 2.4 * a as f32 / COLS as f32;
        let shade = if (a + r) % 2 == 0 {
            Rgb565::new(6, 40, 8)
        } else {
            Rgb565::new(10, 52, 6)
        };
        let p = |aa: usize, z: f32| project(s(aa) * z, -15.0, z, shade);
        return if second {
            [p(a, z0), p(a + 1, z1), p(a, z1)]
        } else {
            [p(a, z0), p(a + 1, z0), p(a + 1, z1)]
        };
    }
    let k = k - GROUND_TRIS;
    let (cx, y0, y1, cz, h) = BOXES[k / 12];
    let (face, second) = ((k % 12) / 2, k % 2 == 1);
    // corners of each face, counter-clockwise seen from outside
    let (xa, xb, za, zb) = (cx - h, cx + h, cz - h, cz + h);
    let q: [(f32, f32, f32); 4] = match face {
        0 => [(xa, y0, za), (xb, y0, za), (xb, y1, za), (xa, y1, za)], // front (-Z)
        1 => [(xb, y0, zb), (xa, y0, zb), (xa, y1, zb), (xb, y1, zb)], // back
        2 => [(xa, y0, zb), (xa, y0, za), (xa, y1, za), (xa, y1, zb)], // left
        3 => [(xb, y0, za), (xb, y0, zb), (xb, y1, zb), (xb, y1, za)], // right
        4 => [(xa, y1, za), (xb, y1, za), (xb, y1, zb), (xa, y1, zb)], // top
        _ => [(xa, y0, zb), (xb, y0, zb), (xb, y0, za), (xa, y0, za)], // bottom
    };
    let color = [
        Rgb565::new(28, 20, 4),
        Rgb565::new(20, 14, 3),
        Rgb565::new(24, 30, 10),
        Rgb565::new(16, 10, 20),
        Rgb565::new(31, 50, 16),
        Rgb565::new(8, 8, 8),
    ][face];
    let c = if (k / 12) % 2 == 1 {
        Rgb565::new(color.b(), color.g(), color.r())
    } else {
        color
    };
    let v = |i: usize| project(q[i].0, q[i].1, q[i].2, c);
    if second {
        [v(0), v(2), v(3)]
    } else {
        [v(0), v(1), v(2)]
    }
}

/// W4 "torus": a rotating mesh drawn from world space (transform, cull, clip, rasterise), as the benchmark workloads
/// define it (README, "Standard scenes"): 320 x 240, depth cleared to the far plane before each of 8 frames, `Less`.
pub mod torus {
    use embedded_graphics_core::pixelcolor::Rgb565;

    use crate::projection::{sin_cos, Camera, Mat4};
    use crate::Error;

    /// Major radius.
    pub const R: f32 = 1.0;
    /// Minor radius.
    pub const MINOR: f32 = 0.35;
    /// Segments around the major circle (`i`).
    pub const SEG_I: usize = 32;
    /// Segments around the minor circle (`j`).
    pub const SEG_J: usize = 16;
    /// Vertices.
    pub const VERTICES: usize = SEG_I * SEG_J;
    /// Triangles.
    pub const TRIANGLES: usize = 2 * SEG_I * SEG_J;
    /// Frames of the benchmark.
    pub const FRAMES: usize = 8;
    /// `W_near`, `W_far`.
    pub const DEPTH: (f32, f32) = (0.5, 100.0);

    /// The palette (RGB565), triangle `k` takes entry `k mod 8`.
    pub const PALETTE: [u16; 8] = [
        0xF800, 0x07E0, 0x001F, 0xFFE0, 0x07FF, 0xF81F, 0xFD20, 0x8410,
    ];

    /// Vertex `(i, j)` at index `j * SEG_I + i`: `((R + r cos phi) cos theta, (R + r cos phi) sin theta, r sin phi)`,
    /// `theta = 2 pi i / 32`, `phi = 2 pi j / 16`, with [`sin_cos`] (f32, so the same bits on every core).
    pub fn positions() -> [[f32; 3]; VERTICES] {
        core::array::from_fn(|k| {
            let (i, j) = (k % SEG_I, k / SEG_I);
            let tau = 2.0 * core::f32::consts::PI;
            let (st, ct) = sin_cos(tau * i as f32 / SEG_I as f32);
            let (sp, cp) = sin_cos(tau * j as f32 / SEG_J as f32);
            let ring = R + MINOR * cp;
            [ring * ct, ring * st, MINOR * sp]
        })
    }

    /// Quad `(i, j)` (row-major, `j` outer) is `(i,j) (i+1,j) (i+1,j+1)` and `(i,j) (i+1,j+1) (i,j+1)`, indices
    /// mod 32 and mod 16: counter-clockwise seen from outside.
    pub fn indices() -> [[u16; 3]; TRIANGLES] {
        core::array::from_fn(|k| {
            let (q, second) = (k / 2, k % 2 == 1);
            let (i, j) = (q % SEG_I, q / SEG_I);
            let v = |di: usize, dj: usize| (((j + dj) % SEG_J) * SEG_I + (i + di) % SEG_I) as u16;
            if second {
                [v(0, 0), v(1, 1), v(0, 1)]
            } else {
                [v(0, 0), v(1, 0), v(1, 1)]
            }
        })
    }

    /// Triangle `k`'s colour.
    pub fn colors() -> [Rgb565; TRIANGLES] {
        core::array::from_fn(|k| {
            embedded_graphics_core::pixelcolor::raw::RawU16::new(PALETTE[k % 8]).into()
        })
    }

    /// Frame `k`'s model matrix: about x by `0.35 k` rad, then about y by `0.6 k` rad.
    pub fn model(k: usize) -> Mat4 {
        Mat4::rotation_x(0.35 * k as f32) * Mat4::rotation_y(0.6 * k as f32)
    }

    /// Eye at `(0, 0, 3)` looking at the origin, up `+y`, vertical field of view 60 degrees, aspect 4:3,
    /// `W_near = 0.5`, `W_far = 100`.
    pub fn camera() -> Result<Camera, Error> {
        Camera::look_at(
            [0.0, 0.0, 3.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            core::f32::consts::FRAC_PI_3,
            4.0 / 3.0,
            DEPTH.0,
            DEPTH.1,
        )
    }
}
