// Moment quantization θ4 (momentlab theta; Peters & Klein 2015, Section 4.3): stored s = A*b(z) + t in [0,1]^4.
// Basis b = (z, z^2, z^3, z^4), m = 4; entropy gain log2|det A| = 12.2783 bits.
// Depth range: z in [0,1] (for depths d in [-1,1], e.g. HDRP's HDIMS path, encode z = 0.5*d + 0.5 and use [0,1] depths in the reconstruction).
// Moment order: the decoder returns b = (z, z^2, z^3, z^4) of the filtered depth distribution, in this order.
// Transform: the 2015 paper's θ4 as published (the one MJP's Shadows sample and Unity HDRP ship; offset 0.035955884801 there, 0.0359558848 in the paper), so engines' decoders read these texels.
// Encoder: each channel as a Chebyshev series in x = 2z - 1 (Clenshaw's recurrence), accurate in f32; clamped to [0,1].
// Store s (16-bit UNORM or 32-bit float), filter linearly, decode the filtered sample.
// Reconstruction: Hamburger or Hausdorff 4MSM with biased moments b' = (1 - α) b + α b*, b* = (0.5, 0.5, 0.5, 0.5);
// α = 3e-5 with 16-bit UNORM storage, α = 2e-6 with 32-bit float storage (Peters & Klein 2015, Sections 4.3 and 5).
// Accuracy: momentlab checks it with every operation rounded on its own (`precise`) and with every a*b + c fused, as drivers may without `precise` (WGSL, GLSL before 4.00 / ES 3.20).
// WGSL has no `precise`: drivers may fuse a*b + c; the accuracy stated holds for both.

fn encodeMoments4(z: f32, s: ptr<function, array<f32, 4>>)
{
    let t_4: f32 = z * 2e0f;
    let t_5: f32 = t_4 - 1e0f; // x = 2z - 1
    let t_6: f32 = t_5 + t_5;
    let t_8: f32 = t_6 * 3.075806796550751e-1f;
    let t_10: f32 = t_8 + 3.177993893623352e-1f;
    let t_11: f32 = t_6 * t_10;
    let t_12: f32 = t_11 - 3.075806796550751e-1f;
    let t_14: f32 = t_12 + (-2.1518763899803162e-1f);
    let t_15: f32 = t_6 * t_14;
    let t_16: f32 = t_15 - t_10;
    let t_18: f32 = t_16 + 1.6422267258167267e-1f;
    let t_19: f32 = t_5 * t_18;
    let t_20: f32 = t_19 - t_14;
    let t_22: f32 = t_20 + 4.2558491230010986e-1f;
    let t_23: f32 = clamp(t_22, 0e0f, 1e0f); // stored channel 0
    let t_25: f32 = t_6 * (-2.7628830075263977e-1f);
    let t_27: f32 = t_25 + 3.533177673816681e-1f;
    let t_28: f32 = t_6 * t_27;
    let t_29: f32 = t_28 - (-2.7628830075263977e-1f);
    let t_31: f32 = t_29 + 2.1212303638458252e-1f;
    let t_32: f32 = t_6 * t_31;
    let t_33: f32 = t_32 - t_27;
    let t_35: f32 = t_33 + 1.4546218514442444e-1f;
    let t_36: f32 = t_5 * t_35;
    let t_37: f32 = t_36 - t_31;
    let t_39: f32 = t_37 + 5.629452466964722e-1f;
    let t_40: f32 = clamp(t_39, 0e0f, 1e0f); // stored channel 1
    let t_42: f32 = t_6 * (-5.198710039258003e-2f);
    let t_44: f32 = t_42 + (-1.2372007966041565e-1f);
    let t_45: f32 = t_6 * t_44;
    let t_46: f32 = t_45 - (-5.198710039258003e-2f);
    let t_48: f32 = t_46 + 5.895322188735008e-2f;
    let t_49: f32 = t_6 * t_48;
    let t_50: f32 = t_49 - t_44;
    let t_52: f32 = t_50 + 5.704388618469238e-1f;
    let t_53: f32 = t_5 * t_52;
    let t_54: f32 = t_53 - t_48;
    let t_56: f32 = t_54 + 4.3975263833999634e-1f;
    let t_57: f32 = clamp(t_56, 0e0f, 1e0f); // stored channel 2
    let t_59: f32 = t_6 * (-1.8728753924369812e-1f);
    let t_61: f32 = t_59 + 3.1250024790097086e-9f;
    let t_62: f32 = t_6 * t_61;
    let t_63: f32 = t_62 - (-1.8728753924369812e-1f);
    let t_65: f32 = t_63 + (-4.7490060329437256e-1f);
    let t_66: f32 = t_6 * t_65;
    let t_67: f32 = t_66 - t_61;
    let t_69: f32 = t_67 + 2.1875003142213245e-8f;
    let t_70: f32 = t_5 * t_69;
    let t_71: f32 = t_70 - t_65;
    let t_73: f32 = t_71 + 6.621881723403931e-1f;
    let t_74: f32 = clamp(t_73, 0e0f, 1e0f); // stored channel 3
    (*s)[0] = t_23;
    (*s)[1] = t_40;
    (*s)[2] = t_57;
    (*s)[3] = t_74;
}

fn decodeMoments4(s: array<f32, 4>, b: ptr<function, array<f32, 4>>)
{
    let t_5: f32 = s[0] - 3.595588356256485e-2f;
    let t_7: f32 = 2.227744162082672e-1f * t_5;
    let t_9: f32 = 7.719728350639343e-2f * s[1];
    let t_10: f32 = t_7 + t_9;
    let t_12: f32 = 7.926986813545227e-1f * s[2];
    let t_13: f32 = t_10 + t_12;
    let t_15: f32 = 3.194175660610199e-2f * s[3];
    let t_16: f32 = t_13 + t_15;
    let t_18: f32 = 1.5496793389320374e-1f * t_5;
    let t_20: f32 = 1.3946294784545898e-1f * s[1];
    let t_21: f32 = t_18 + t_20;
    let t_23: f32 = 7.96341598033905e-1f * s[2];
    let t_24: f32 = t_21 + t_23;
    let t_26: f32 = (-1.7228232324123383e-1f) * s[3];
    let t_27: f32 = t_24 + t_26;
    let t_29: f32 = 1.4519889652729034e-1f * t_5;
    let t_31: f32 = 2.1202021837234497e-1f * s[1];
    let t_32: f32 = t_29 + t_31;
    let t_34: f32 = 7.258694767951965e-1f * s[2];
    let t_35: f32 = t_32 + t_34;
    let t_37: f32 = (-2.7580147981643677e-1f) * s[3];
    let t_38: f32 = t_35 + t_37;
    let t_40: f32 = 1.6312745213508606e-1f * t_5;
    let t_42: f32 = 2.5914323329925537e-1f * s[1];
    let t_43: f32 = t_40 + t_42;
    let t_45: f32 = 6.539092659950256e-1f * s[2];
    let t_46: f32 = t_43 + t_45;
    let t_48: f32 = (-3.3761316537857056e-1f) * s[3];
    let t_49: f32 = t_46 + t_48;
    (*b)[0] = t_16;
    (*b)[1] = t_27;
    (*b)[2] = t_38;
    (*b)[3] = t_49;
}

fn encodeMoments4Vec(z: f32) -> vec4<f32>
{
    let t_4: f32 = z * 2e0f;
    let t_5: f32 = t_4 - 1e0f; // x = 2z - 1
    let t_6: f32 = t_5 + t_5;
    let t_8: f32 = t_6 * 3.075806796550751e-1f;
    let t_10: f32 = t_8 + 3.177993893623352e-1f;
    let t_11: f32 = t_6 * t_10;
    let t_12: f32 = t_11 - 3.075806796550751e-1f;
    let t_14: f32 = t_12 + (-2.1518763899803162e-1f);
    let t_15: f32 = t_6 * t_14;
    let t_16: f32 = t_15 - t_10;
    let t_18: f32 = t_16 + 1.6422267258167267e-1f;
    let t_19: f32 = t_5 * t_18;
    let t_20: f32 = t_19 - t_14;
    let t_22: f32 = t_20 + 4.2558491230010986e-1f;
    let t_23: f32 = clamp(t_22, 0e0f, 1e0f); // stored channel 0
    let t_25: f32 = t_6 * (-2.7628830075263977e-1f);
    let t_27: f32 = t_25 + 3.533177673816681e-1f;
    let t_28: f32 = t_6 * t_27;
    let t_29: f32 = t_28 - (-2.7628830075263977e-1f);
    let t_31: f32 = t_29 + 2.1212303638458252e-1f;
    let t_32: f32 = t_6 * t_31;
    let t_33: f32 = t_32 - t_27;
    let t_35: f32 = t_33 + 1.4546218514442444e-1f;
    let t_36: f32 = t_5 * t_35;
    let t_37: f32 = t_36 - t_31;
    let t_39: f32 = t_37 + 5.629452466964722e-1f;
    let t_40: f32 = clamp(t_39, 0e0f, 1e0f); // stored channel 1
    let t_42: f32 = t_6 * (-5.198710039258003e-2f);
    let t_44: f32 = t_42 + (-1.2372007966041565e-1f);
    let t_45: f32 = t_6 * t_44;
    let t_46: f32 = t_45 - (-5.198710039258003e-2f);
    let t_48: f32 = t_46 + 5.895322188735008e-2f;
    let t_49: f32 = t_6 * t_48;
    let t_50: f32 = t_49 - t_44;
    let t_52: f32 = t_50 + 5.704388618469238e-1f;
    let t_53: f32 = t_5 * t_52;
    let t_54: f32 = t_53 - t_48;
    let t_56: f32 = t_54 + 4.3975263833999634e-1f;
    let t_57: f32 = clamp(t_56, 0e0f, 1e0f); // stored channel 2
    let t_59: f32 = t_6 * (-1.8728753924369812e-1f);
    let t_61: f32 = t_59 + 3.1250024790097086e-9f;
    let t_62: f32 = t_6 * t_61;
    let t_63: f32 = t_62 - (-1.8728753924369812e-1f);
    let t_65: f32 = t_63 + (-4.7490060329437256e-1f);
    let t_66: f32 = t_6 * t_65;
    let t_67: f32 = t_66 - t_61;
    let t_69: f32 = t_67 + 2.1875003142213245e-8f;
    let t_70: f32 = t_5 * t_69;
    let t_71: f32 = t_70 - t_65;
    let t_73: f32 = t_71 + 6.621881723403931e-1f;
    let t_74: f32 = clamp(t_73, 0e0f, 1e0f); // stored channel 3
    return vec4<f32>(t_23, t_40, t_57, t_74);
}

fn decodeMoments4Vec(s0123: vec4<f32>) -> vec4<f32>
{
    let t_5: f32 = s0123.x - 3.595588356256485e-2f;
    let t_7: f32 = 2.227744162082672e-1f * t_5;
    let t_9: f32 = 7.719728350639343e-2f * s0123.y;
    let t_10: f32 = t_7 + t_9;
    let t_12: f32 = 7.926986813545227e-1f * s0123.z;
    let t_13: f32 = t_10 + t_12;
    let t_15: f32 = 3.194175660610199e-2f * s0123.w;
    let t_16: f32 = t_13 + t_15;
    let t_18: f32 = 1.5496793389320374e-1f * t_5;
    let t_20: f32 = 1.3946294784545898e-1f * s0123.y;
    let t_21: f32 = t_18 + t_20;
    let t_23: f32 = 7.96341598033905e-1f * s0123.z;
    let t_24: f32 = t_21 + t_23;
    let t_26: f32 = (-1.7228232324123383e-1f) * s0123.w;
    let t_27: f32 = t_24 + t_26;
    let t_29: f32 = 1.4519889652729034e-1f * t_5;
    let t_31: f32 = 2.1202021837234497e-1f * s0123.y;
    let t_32: f32 = t_29 + t_31;
    let t_34: f32 = 7.258694767951965e-1f * s0123.z;
    let t_35: f32 = t_32 + t_34;
    let t_37: f32 = (-2.7580147981643677e-1f) * s0123.w;
    let t_38: f32 = t_35 + t_37;
    let t_40: f32 = 1.6312745213508606e-1f * t_5;
    let t_42: f32 = 2.5914323329925537e-1f * s0123.y;
    let t_43: f32 = t_40 + t_42;
    let t_45: f32 = 6.539092659950256e-1f * s0123.z;
    let t_46: f32 = t_43 + t_45;
    let t_48: f32 = (-3.3761316537857056e-1f) * s0123.w;
    let t_49: f32 = t_46 + t_48;
    return vec4<f32>(t_16, t_27, t_38, t_49);
}
