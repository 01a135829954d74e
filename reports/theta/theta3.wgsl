// Moment quantization θ3 (momentlab theta; Peters & Klein 2015, Section 4.3): stored s = A*b(z) + t in [0,1]^3.
// Basis b = (z, z^2, z^3), m = 3; entropy gain log2|det A| = 6.2075 bits.
// Depth range: z in [0,1] (for depths d in [-1,1], e.g. HDRP's HDIMS path, encode z = 0.5*d + 0.5 and use [0,1] depths in the reconstruction).
// Moment order: the decoder returns b = (z, z^2, z^3) of the filtered depth distribution, in this order.
// Channel order: as found by momentlab's search.
// Encoder: each channel as a Chebyshev series in x = 2z - 1 (Clenshaw's recurrence), accurate in f32; clamped to [0,1].
// Store s (16-bit UNORM or 32-bit float), filter linearly, decode the filtered sample.
// Moment bias α, b*: depend on the reconstruction (none recommended for this m).
// Accuracy: momentlab checks it with every operation rounded on its own (`precise`) and with every a*b + c fused, as drivers may without `precise` (WGSL, GLSL before 4.00 / ES 3.20).
// WGSL has no `precise`: drivers may fuse a*b + c; the accuracy stated holds for both.

fn encodeMoments3(z: f32, s: ptr<function, array<f32, 3>>)
{
    let t_4: f32 = z * 2e0f;
    let t_5: f32 = t_4 - 1e0f; // x = 2z - 1
    let t_6: f32 = t_5 + t_5;
    let t_8: f32 = t_6 * 5e-1f;
    let t_10: f32 = t_8 + 5.075151410238732e-11f;
    let t_11: f32 = t_6 * t_10;
    let t_12: f32 = t_11 - 5e-1f;
    let t_14: f32 = t_12 + 5.075082021299693e-11f;
    let t_15: f32 = t_5 * t_14;
    let t_16: f32 = t_15 - t_10;
    let t_18: f32 = t_16 + 5e-1f;
    let t_19: f32 = clamp(t_18, 0e0f, 1e0f); // stored channel 0
    let t_21: f32 = t_6 * 9.622305631637573e-2f;
    let t_23: f32 = t_21 + 1.363330284220865e-7f;
    let t_24: f32 = t_6 * t_23;
    let t_25: f32 = t_24 - 9.622305631637573e-2f;
    let t_27: f32 = t_25 + (-5.773502588272095e-1f);
    let t_28: f32 = t_5 * t_27;
    let t_29: f32 = t_28 - t_23;
    let t_31: f32 = t_29 + 4.999999403953552e-1f;
    let t_32: f32 = clamp(t_31, 0e0f, 1e0f); // stored channel 1
    let t_34: f32 = t_6 * 5.394103936851025e-7f;
    let t_36: f32 = t_34 + (-5e-1f);
    let t_37: f32 = t_6 * t_36;
    let t_38: f32 = t_37 - 5.394103936851025e-7f;
    let t_40: f32 = t_38 + (-5.396432243287563e-7f);
    let t_41: f32 = t_5 * t_40;
    let t_42: f32 = t_41 - t_36;
    let t_44: f32 = t_42 + 5e-1f;
    let t_45: f32 = clamp(t_44, 0e0f, 1e0f); // stored channel 2
    (*s)[0] = t_19;
    (*s)[1] = t_32;
    (*s)[2] = t_45;
}

fn decodeMoments3(s: array<f32, 3>, b: ptr<function, array<f32, 3>>)
{
    let t_4: f32 = s[0] - 4.999999858590343e-10f;
    let t_6: f32 = s[1] - 9.811272621154785e-1f;
    let t_8: f32 = s[2] - 9.656611066333198e-10f;
    let t_10: f32 = 1.6666321456432343e-1f * t_4;
    let t_12: f32 = (-8.660253882408142e-1f) * t_6;
    let t_13: f32 = t_10 + t_12;
    let t_15: f32 = (-2.3611882227214664e-7f) * t_8;
    let t_16: f32 = t_13 + t_15;
    let t_18: f32 = 1.6666343808174133e-1f * t_4;
    let t_20: f32 = (-8.660251498222351e-1f) * t_6;
    let t_21: f32 = t_18 + t_20;
    let t_23: f32 = (-2.500002384185791e-1f) * t_8;
    let t_24: f32 = t_21 + t_23;
    let t_26: f32 = 2.187471091747284e-1f * t_4;
    let t_28: f32 = (-8.118984699249268e-1f) * t_6;
    let t_29: f32 = t_26 + t_28;
    let t_31: f32 = (-3.750002086162567e-1f) * t_8;
    let t_32: f32 = t_29 + t_31;
    (*b)[0] = t_16;
    (*b)[1] = t_24;
    (*b)[2] = t_32;
}

fn encodeMoments3Vec(z: f32) -> vec3<f32>
{
    let t_4: f32 = z * 2e0f;
    let t_5: f32 = t_4 - 1e0f; // x = 2z - 1
    let t_6: f32 = t_5 + t_5;
    let t_8: f32 = t_6 * 5e-1f;
    let t_10: f32 = t_8 + 5.075151410238732e-11f;
    let t_11: f32 = t_6 * t_10;
    let t_12: f32 = t_11 - 5e-1f;
    let t_14: f32 = t_12 + 5.075082021299693e-11f;
    let t_15: f32 = t_5 * t_14;
    let t_16: f32 = t_15 - t_10;
    let t_18: f32 = t_16 + 5e-1f;
    let t_19: f32 = clamp(t_18, 0e0f, 1e0f); // stored channel 0
    let t_21: f32 = t_6 * 9.622305631637573e-2f;
    let t_23: f32 = t_21 + 1.363330284220865e-7f;
    let t_24: f32 = t_6 * t_23;
    let t_25: f32 = t_24 - 9.622305631637573e-2f;
    let t_27: f32 = t_25 + (-5.773502588272095e-1f);
    let t_28: f32 = t_5 * t_27;
    let t_29: f32 = t_28 - t_23;
    let t_31: f32 = t_29 + 4.999999403953552e-1f;
    let t_32: f32 = clamp(t_31, 0e0f, 1e0f); // stored channel 1
    let t_34: f32 = t_6 * 5.394103936851025e-7f;
    let t_36: f32 = t_34 + (-5e-1f);
    let t_37: f32 = t_6 * t_36;
    let t_38: f32 = t_37 - 5.394103936851025e-7f;
    let t_40: f32 = t_38 + (-5.396432243287563e-7f);
    let t_41: f32 = t_5 * t_40;
    let t_42: f32 = t_41 - t_36;
    let t_44: f32 = t_42 + 5e-1f;
    let t_45: f32 = clamp(t_44, 0e0f, 1e0f); // stored channel 2
    return vec3<f32>(t_19, t_32, t_45);
}

fn decodeMoments3Vec(s012: vec3<f32>) -> vec3<f32>
{
    let t_4: f32 = s012.x - 4.999999858590343e-10f;
    let t_6: f32 = s012.y - 9.811272621154785e-1f;
    let t_8: f32 = s012.z - 9.656611066333198e-10f;
    let t_10: f32 = 1.6666321456432343e-1f * t_4;
    let t_12: f32 = (-8.660253882408142e-1f) * t_6;
    let t_13: f32 = t_10 + t_12;
    let t_15: f32 = (-2.3611882227214664e-7f) * t_8;
    let t_16: f32 = t_13 + t_15;
    let t_18: f32 = 1.6666343808174133e-1f * t_4;
    let t_20: f32 = (-8.660251498222351e-1f) * t_6;
    let t_21: f32 = t_18 + t_20;
    let t_23: f32 = (-2.500002384185791e-1f) * t_8;
    let t_24: f32 = t_21 + t_23;
    let t_26: f32 = 2.187471091747284e-1f * t_4;
    let t_28: f32 = (-8.118984699249268e-1f) * t_6;
    let t_29: f32 = t_26 + t_28;
    let t_31: f32 = (-3.750002086162567e-1f) * t_8;
    let t_32: f32 = t_29 + t_31;
    return vec3<f32>(t_16, t_24, t_32);
}
