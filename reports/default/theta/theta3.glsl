// Moment quantization θ3 (momentlab theta; Peters & Klein 2015, Section 4.3): stored s = A*b(z) + t in [0,1]^3.
// Basis b = (z, z^2, z^3), m = 3; entropy gain log2|det A| = 6.2075 bits.
// Depth range: z in [0,1] (for depths d in [-1,1], e.g. HDRP's HDIMS path, encode z = 0.5*d + 0.5 and use [0,1] depths in the reconstruction).
// Moment order: the decoder returns b = (z, z^2, z^3) of the filtered depth distribution, in this order.
// Channel order: as found by momentlab's search.
// Encoder: each channel as a Chebyshev series in x = 2z - 1 (Clenshaw's recurrence), accurate in f32; clamped to [0,1].
// Store s (16-bit UNORM or 32-bit float), filter linearly, decode the filtered sample.
// Moment bias α, b*: depend on the reconstruction (none recommended for this m).
// Accuracy: momentlab checks it with every operation rounded on its own (`precise`) and with every a*b + c fused, as drivers may without `precise` (WGSL, GLSL before 4.00 / ES 3.20).
// MOMENTLAB_PRECISE: `precise` (no fused a*b + c) in GLSL >= 4.00 and GLSL ES >= 3.20, empty in older GLSL; define it before this text to override.
#ifndef MOMENTLAB_PRECISE
#if (defined(GL_ES) && __VERSION__ >= 320) || (!defined(GL_ES) && __VERSION__ >= 400)
#define MOMENTLAB_PRECISE precise
#else
#define MOMENTLAB_PRECISE
#endif
#endif

void encodeMoments3(float z, out float s[3])
{
    MOMENTLAB_PRECISE float t_4 = z * 2e0;
    MOMENTLAB_PRECISE float t_5 = t_4 - 1e0; // x = 2z - 1
    MOMENTLAB_PRECISE float t_6 = t_5 + t_5;
    MOMENTLAB_PRECISE float t_8 = t_6 * 5e-1;
    MOMENTLAB_PRECISE float t_10 = t_8 + 5.075151410238732e-11;
    MOMENTLAB_PRECISE float t_11 = t_6 * t_10;
    MOMENTLAB_PRECISE float t_12 = t_11 - 5e-1;
    MOMENTLAB_PRECISE float t_14 = t_12 + 5.075082021299693e-11;
    MOMENTLAB_PRECISE float t_15 = t_5 * t_14;
    MOMENTLAB_PRECISE float t_16 = t_15 - t_10;
    MOMENTLAB_PRECISE float t_18 = t_16 + 5e-1;
    MOMENTLAB_PRECISE float t_19 = clamp(t_18, 0e0, 1e0); // stored channel 0
    MOMENTLAB_PRECISE float t_21 = t_6 * 9.622305631637573e-2;
    MOMENTLAB_PRECISE float t_23 = t_21 + 1.363330284220865e-7;
    MOMENTLAB_PRECISE float t_24 = t_6 * t_23;
    MOMENTLAB_PRECISE float t_25 = t_24 - 9.622305631637573e-2;
    MOMENTLAB_PRECISE float t_27 = t_25 + (-5.773502588272095e-1);
    MOMENTLAB_PRECISE float t_28 = t_5 * t_27;
    MOMENTLAB_PRECISE float t_29 = t_28 - t_23;
    MOMENTLAB_PRECISE float t_31 = t_29 + 4.999999403953552e-1;
    MOMENTLAB_PRECISE float t_32 = clamp(t_31, 0e0, 1e0); // stored channel 1
    MOMENTLAB_PRECISE float t_34 = t_6 * 5.394103936851025e-7;
    MOMENTLAB_PRECISE float t_36 = t_34 + (-5e-1);
    MOMENTLAB_PRECISE float t_37 = t_6 * t_36;
    MOMENTLAB_PRECISE float t_38 = t_37 - 5.394103936851025e-7;
    MOMENTLAB_PRECISE float t_40 = t_38 + (-5.396432243287563e-7);
    MOMENTLAB_PRECISE float t_41 = t_5 * t_40;
    MOMENTLAB_PRECISE float t_42 = t_41 - t_36;
    MOMENTLAB_PRECISE float t_44 = t_42 + 5e-1;
    MOMENTLAB_PRECISE float t_45 = clamp(t_44, 0e0, 1e0); // stored channel 2
    s[0] = t_19;
    s[1] = t_32;
    s[2] = t_45;
}

void decodeMoments3(float s[3], out float b[3])
{
    MOMENTLAB_PRECISE float t_4 = s[0] - 4.999999858590343e-10;
    MOMENTLAB_PRECISE float t_6 = s[1] - 9.811272621154785e-1;
    MOMENTLAB_PRECISE float t_8 = s[2] - 9.656611066333198e-10;
    MOMENTLAB_PRECISE float t_10 = 1.6666321456432343e-1 * t_4;
    MOMENTLAB_PRECISE float t_12 = (-8.660253882408142e-1) * t_6;
    MOMENTLAB_PRECISE float t_13 = t_10 + t_12;
    MOMENTLAB_PRECISE float t_15 = (-2.3611882227214664e-7) * t_8;
    MOMENTLAB_PRECISE float t_16 = t_13 + t_15;
    MOMENTLAB_PRECISE float t_18 = 1.6666343808174133e-1 * t_4;
    MOMENTLAB_PRECISE float t_20 = (-8.660251498222351e-1) * t_6;
    MOMENTLAB_PRECISE float t_21 = t_18 + t_20;
    MOMENTLAB_PRECISE float t_23 = (-2.500002384185791e-1) * t_8;
    MOMENTLAB_PRECISE float t_24 = t_21 + t_23;
    MOMENTLAB_PRECISE float t_26 = 2.187471091747284e-1 * t_4;
    MOMENTLAB_PRECISE float t_28 = (-8.118984699249268e-1) * t_6;
    MOMENTLAB_PRECISE float t_29 = t_26 + t_28;
    MOMENTLAB_PRECISE float t_31 = (-3.750002086162567e-1) * t_8;
    MOMENTLAB_PRECISE float t_32 = t_29 + t_31;
    b[0] = t_16;
    b[1] = t_24;
    b[2] = t_32;
}

vec3 encodeMoments3Vec(float z)
{
    MOMENTLAB_PRECISE float t_4 = z * 2e0;
    MOMENTLAB_PRECISE float t_5 = t_4 - 1e0; // x = 2z - 1
    MOMENTLAB_PRECISE float t_6 = t_5 + t_5;
    MOMENTLAB_PRECISE float t_8 = t_6 * 5e-1;
    MOMENTLAB_PRECISE float t_10 = t_8 + 5.075151410238732e-11;
    MOMENTLAB_PRECISE float t_11 = t_6 * t_10;
    MOMENTLAB_PRECISE float t_12 = t_11 - 5e-1;
    MOMENTLAB_PRECISE float t_14 = t_12 + 5.075082021299693e-11;
    MOMENTLAB_PRECISE float t_15 = t_5 * t_14;
    MOMENTLAB_PRECISE float t_16 = t_15 - t_10;
    MOMENTLAB_PRECISE float t_18 = t_16 + 5e-1;
    MOMENTLAB_PRECISE float t_19 = clamp(t_18, 0e0, 1e0); // stored channel 0
    MOMENTLAB_PRECISE float t_21 = t_6 * 9.622305631637573e-2;
    MOMENTLAB_PRECISE float t_23 = t_21 + 1.363330284220865e-7;
    MOMENTLAB_PRECISE float t_24 = t_6 * t_23;
    MOMENTLAB_PRECISE float t_25 = t_24 - 9.622305631637573e-2;
    MOMENTLAB_PRECISE float t_27 = t_25 + (-5.773502588272095e-1);
    MOMENTLAB_PRECISE float t_28 = t_5 * t_27;
    MOMENTLAB_PRECISE float t_29 = t_28 - t_23;
    MOMENTLAB_PRECISE float t_31 = t_29 + 4.999999403953552e-1;
    MOMENTLAB_PRECISE float t_32 = clamp(t_31, 0e0, 1e0); // stored channel 1
    MOMENTLAB_PRECISE float t_34 = t_6 * 5.394103936851025e-7;
    MOMENTLAB_PRECISE float t_36 = t_34 + (-5e-1);
    MOMENTLAB_PRECISE float t_37 = t_6 * t_36;
    MOMENTLAB_PRECISE float t_38 = t_37 - 5.394103936851025e-7;
    MOMENTLAB_PRECISE float t_40 = t_38 + (-5.396432243287563e-7);
    MOMENTLAB_PRECISE float t_41 = t_5 * t_40;
    MOMENTLAB_PRECISE float t_42 = t_41 - t_36;
    MOMENTLAB_PRECISE float t_44 = t_42 + 5e-1;
    MOMENTLAB_PRECISE float t_45 = clamp(t_44, 0e0, 1e0); // stored channel 2
    return vec3(t_19, t_32, t_45);
}

vec3 decodeMoments3Vec(vec3 s012)
{
    MOMENTLAB_PRECISE float t_4 = s012.x - 4.999999858590343e-10;
    MOMENTLAB_PRECISE float t_6 = s012.y - 9.811272621154785e-1;
    MOMENTLAB_PRECISE float t_8 = s012.z - 9.656611066333198e-10;
    MOMENTLAB_PRECISE float t_10 = 1.6666321456432343e-1 * t_4;
    MOMENTLAB_PRECISE float t_12 = (-8.660253882408142e-1) * t_6;
    MOMENTLAB_PRECISE float t_13 = t_10 + t_12;
    MOMENTLAB_PRECISE float t_15 = (-2.3611882227214664e-7) * t_8;
    MOMENTLAB_PRECISE float t_16 = t_13 + t_15;
    MOMENTLAB_PRECISE float t_18 = 1.6666343808174133e-1 * t_4;
    MOMENTLAB_PRECISE float t_20 = (-8.660251498222351e-1) * t_6;
    MOMENTLAB_PRECISE float t_21 = t_18 + t_20;
    MOMENTLAB_PRECISE float t_23 = (-2.500002384185791e-1) * t_8;
    MOMENTLAB_PRECISE float t_24 = t_21 + t_23;
    MOMENTLAB_PRECISE float t_26 = 2.187471091747284e-1 * t_4;
    MOMENTLAB_PRECISE float t_28 = (-8.118984699249268e-1) * t_6;
    MOMENTLAB_PRECISE float t_29 = t_26 + t_28;
    MOMENTLAB_PRECISE float t_31 = (-3.750002086162567e-1) * t_8;
    MOMENTLAB_PRECISE float t_32 = t_29 + t_31;
    return vec3(t_16, t_24, t_32);
}
