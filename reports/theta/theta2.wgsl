// Moment quantization θ2 (momentlab theta; Peters & Klein 2015, Section 4.3): stored s = A*b(z) + t in [0,1]^2.
// Basis b = (z, z^2), m = 2; entropy gain log2|det A| = 2.0000 bits.
// Depth range: z in [0,1] (for depths d in [-1,1], e.g. HDRP's HDIMS path, encode z = 0.5*d + 0.5 and use [0,1] depths in the reconstruction).
// Moment order: the decoder returns b = (z, z^2) of the filtered depth distribution, in this order.
// Transform: the 2015 paper's θ2 as published (rows [1, 0] and [4, -4]).
// Encoder: each channel as a Chebyshev series in x = 2z - 1 (Clenshaw's recurrence), accurate in f32; clamped to [0,1].
// Store s (16-bit UNORM or 32-bit float), filter linearly, decode the filtered sample.
// Reconstruction: VSM (Chebyshev/Cantelli); no moment bias α, clamp the variance from below instead.
// Accuracy: momentlab checks it with every operation rounded on its own (`precise`) and with every a*b + c fused, as drivers may without `precise` (WGSL, GLSL before 4.00 / ES 3.20).
// WGSL has no `precise`: drivers may fuse a*b + c; the accuracy stated holds for both.

fn encodeMoments2(z: f32, s: ptr<function, array<f32, 2>>)
{
    let t_4: f32 = z * 2e0f;
    let t_5: f32 = t_4 - 1e0f; // x = 2z - 1
    let t_6: f32 = t_5 + t_5;
    let t_8: f32 = t_6 * 9.71445146547012e-17f;
    let t_10: f32 = t_8 + 5e-1f;
    let t_11: f32 = t_5 * t_10;
    let t_12: f32 = t_11 - 9.71445146547012e-17f;
    let t_14: f32 = t_12 + 5e-1f;
    let t_15: f32 = clamp(t_14, 0e0f, 1e0f); // stored channel 0
    let t_17: f32 = t_6 * (-5e-1f);
    let t_19: f32 = t_17 + (-1.6653345369377348e-16f);
    let t_20: f32 = t_5 * t_19;
    let t_21: f32 = t_20 - (-5e-1f);
    let t_23: f32 = t_21 + 5e-1f;
    let t_24: f32 = clamp(t_23, 0e0f, 1e0f); // stored channel 1
    (*s)[0] = t_15;
    (*s)[1] = t_24;
}

fn decodeMoments2(s: array<f32, 2>, b: ptr<function, array<f32, 2>>)
{
    let t_3: f32 = 1e0f * s[0];
    let t_5: f32 = 0e0f * s[1];
    let t_6: f32 = t_3 + t_5;
    let t_8: f32 = 1e0f * s[0];
    let t_10: f32 = (-2.5e-1f) * s[1];
    let t_11: f32 = t_8 + t_10;
    (*b)[0] = t_6;
    (*b)[1] = t_11;
}

fn encodeMoments2Vec(z: f32) -> vec2<f32>
{
    let t_4: f32 = z * 2e0f;
    let t_5: f32 = t_4 - 1e0f; // x = 2z - 1
    let t_6: f32 = t_5 + t_5;
    let t_8: f32 = t_6 * 9.71445146547012e-17f;
    let t_10: f32 = t_8 + 5e-1f;
    let t_11: f32 = t_5 * t_10;
    let t_12: f32 = t_11 - 9.71445146547012e-17f;
    let t_14: f32 = t_12 + 5e-1f;
    let t_15: f32 = clamp(t_14, 0e0f, 1e0f); // stored channel 0
    let t_17: f32 = t_6 * (-5e-1f);
    let t_19: f32 = t_17 + (-1.6653345369377348e-16f);
    let t_20: f32 = t_5 * t_19;
    let t_21: f32 = t_20 - (-5e-1f);
    let t_23: f32 = t_21 + 5e-1f;
    let t_24: f32 = clamp(t_23, 0e0f, 1e0f); // stored channel 1
    return vec2<f32>(t_15, t_24);
}

fn decodeMoments2Vec(s01: vec2<f32>) -> vec2<f32>
{
    let t_3: f32 = 1e0f * s01.x;
    let t_5: f32 = 0e0f * s01.y;
    let t_6: f32 = t_3 + t_5;
    let t_8: f32 = 1e0f * s01.x;
    let t_10: f32 = (-2.5e-1f) * s01.y;
    let t_11: f32 = t_8 + t_10;
    return vec2<f32>(t_6, t_11);
}
