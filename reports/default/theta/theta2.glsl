// Moment quantization θ2 (momentlab theta; Peters & Klein 2015, Section 4.3): stored s = A*b(z) + t in [0,1]^2.
// Basis b = (z, z^2), m = 2; entropy gain log2|det A| = 2.0000 bits.
// Depth range: z in [0,1] (for depths d in [-1,1], e.g. HDRP's HDIMS path, encode z = 0.5*d + 0.5 and use [0,1] depths in the reconstruction).
// Moment order: the decoder returns b = (z, z^2) of the filtered depth distribution, in this order.
// Transform: the 2015 paper's θ2 as published (rows [1, 0] and [4, -4]).
// Encoder: each channel as a Chebyshev series in x = 2z - 1 (Clenshaw's recurrence), accurate in f32; clamped to [0,1].
// Store s (16-bit UNORM or 32-bit float), filter linearly, decode the filtered sample.
// Reconstruction: VSM (Chebyshev/Cantelli); no moment bias α, clamp the variance from below instead.
// Accuracy: momentlab checks it with every operation rounded on its own (`precise`) and with every a*b + c fused, as drivers may without `precise` (WGSL, GLSL before 4.00 / ES 3.20).
// MOMENTLAB_PRECISE: `precise` (no fused a*b + c) in GLSL >= 4.00 and GLSL ES >= 3.20, empty in older GLSL; define it before this text to override.
#ifndef MOMENTLAB_PRECISE
#if (defined(GL_ES) && __VERSION__ >= 320) || (!defined(GL_ES) && __VERSION__ >= 400)
#define MOMENTLAB_PRECISE precise
#else
#define MOMENTLAB_PRECISE
#endif
#endif

void encodeMoments2(float z, out float s[2])
{
    MOMENTLAB_PRECISE float t_4 = z * 2e0;
    MOMENTLAB_PRECISE float t_5 = t_4 - 1e0; // x = 2z - 1
    MOMENTLAB_PRECISE float t_6 = t_5 + t_5;
    MOMENTLAB_PRECISE float t_8 = t_6 * 9.71445146547012e-17;
    MOMENTLAB_PRECISE float t_10 = t_8 + 5e-1;
    MOMENTLAB_PRECISE float t_11 = t_5 * t_10;
    MOMENTLAB_PRECISE float t_12 = t_11 - 9.71445146547012e-17;
    MOMENTLAB_PRECISE float t_14 = t_12 + 5e-1;
    MOMENTLAB_PRECISE float t_15 = clamp(t_14, 0e0, 1e0); // stored channel 0
    MOMENTLAB_PRECISE float t_17 = t_6 * (-5e-1);
    MOMENTLAB_PRECISE float t_19 = t_17 + (-1.6653345369377348e-16);
    MOMENTLAB_PRECISE float t_20 = t_5 * t_19;
    MOMENTLAB_PRECISE float t_21 = t_20 - (-5e-1);
    MOMENTLAB_PRECISE float t_23 = t_21 + 5e-1;
    MOMENTLAB_PRECISE float t_24 = clamp(t_23, 0e0, 1e0); // stored channel 1
    s[0] = t_15;
    s[1] = t_24;
}

void decodeMoments2(float s[2], out float b[2])
{
    MOMENTLAB_PRECISE float t_3 = 1e0 * s[0];
    MOMENTLAB_PRECISE float t_5 = 0e0 * s[1];
    MOMENTLAB_PRECISE float t_6 = t_3 + t_5;
    MOMENTLAB_PRECISE float t_8 = 1e0 * s[0];
    MOMENTLAB_PRECISE float t_10 = (-2.5e-1) * s[1];
    MOMENTLAB_PRECISE float t_11 = t_8 + t_10;
    b[0] = t_6;
    b[1] = t_11;
}

vec2 encodeMoments2Vec(float z)
{
    MOMENTLAB_PRECISE float t_4 = z * 2e0;
    MOMENTLAB_PRECISE float t_5 = t_4 - 1e0; // x = 2z - 1
    MOMENTLAB_PRECISE float t_6 = t_5 + t_5;
    MOMENTLAB_PRECISE float t_8 = t_6 * 9.71445146547012e-17;
    MOMENTLAB_PRECISE float t_10 = t_8 + 5e-1;
    MOMENTLAB_PRECISE float t_11 = t_5 * t_10;
    MOMENTLAB_PRECISE float t_12 = t_11 - 9.71445146547012e-17;
    MOMENTLAB_PRECISE float t_14 = t_12 + 5e-1;
    MOMENTLAB_PRECISE float t_15 = clamp(t_14, 0e0, 1e0); // stored channel 0
    MOMENTLAB_PRECISE float t_17 = t_6 * (-5e-1);
    MOMENTLAB_PRECISE float t_19 = t_17 + (-1.6653345369377348e-16);
    MOMENTLAB_PRECISE float t_20 = t_5 * t_19;
    MOMENTLAB_PRECISE float t_21 = t_20 - (-5e-1);
    MOMENTLAB_PRECISE float t_23 = t_21 + 5e-1;
    MOMENTLAB_PRECISE float t_24 = clamp(t_23, 0e0, 1e0); // stored channel 1
    return vec2(t_15, t_24);
}

vec2 decodeMoments2Vec(vec2 s01)
{
    MOMENTLAB_PRECISE float t_3 = 1e0 * s01.x;
    MOMENTLAB_PRECISE float t_5 = 0e0 * s01.y;
    MOMENTLAB_PRECISE float t_6 = t_3 + t_5;
    MOMENTLAB_PRECISE float t_8 = 1e0 * s01.x;
    MOMENTLAB_PRECISE float t_10 = (-2.5e-1) * s01.y;
    MOMENTLAB_PRECISE float t_11 = t_8 + t_10;
    return vec2(t_6, t_11);
}
