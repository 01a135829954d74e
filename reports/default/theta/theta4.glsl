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
// MOMENTLAB_PRECISE: `precise` (no fused a*b + c) in GLSL >= 4.00 and GLSL ES >= 3.20, empty in older GLSL; define it before this text to override.
#ifndef MOMENTLAB_PRECISE
#if (defined(GL_ES) && __VERSION__ >= 320) || (!defined(GL_ES) && __VERSION__ >= 400)
#define MOMENTLAB_PRECISE precise
#else
#define MOMENTLAB_PRECISE
#endif
#endif

void encodeMoments4(float z, out float s[4])
{
    MOMENTLAB_PRECISE float t_4 = z * 2e0;
    MOMENTLAB_PRECISE float t_5 = t_4 - 1e0; // x = 2z - 1
    MOMENTLAB_PRECISE float t_6 = t_5 + t_5;
    MOMENTLAB_PRECISE float t_8 = t_6 * 3.075806796550751e-1;
    MOMENTLAB_PRECISE float t_10 = t_8 + 3.177993893623352e-1;
    MOMENTLAB_PRECISE float t_11 = t_6 * t_10;
    MOMENTLAB_PRECISE float t_12 = t_11 - 3.075806796550751e-1;
    MOMENTLAB_PRECISE float t_14 = t_12 + (-2.1518763899803162e-1);
    MOMENTLAB_PRECISE float t_15 = t_6 * t_14;
    MOMENTLAB_PRECISE float t_16 = t_15 - t_10;
    MOMENTLAB_PRECISE float t_18 = t_16 + 1.6422267258167267e-1;
    MOMENTLAB_PRECISE float t_19 = t_5 * t_18;
    MOMENTLAB_PRECISE float t_20 = t_19 - t_14;
    MOMENTLAB_PRECISE float t_22 = t_20 + 4.2558491230010986e-1;
    MOMENTLAB_PRECISE float t_23 = clamp(t_22, 0e0, 1e0); // stored channel 0
    MOMENTLAB_PRECISE float t_25 = t_6 * (-2.7628830075263977e-1);
    MOMENTLAB_PRECISE float t_27 = t_25 + 3.533177673816681e-1;
    MOMENTLAB_PRECISE float t_28 = t_6 * t_27;
    MOMENTLAB_PRECISE float t_29 = t_28 - (-2.7628830075263977e-1);
    MOMENTLAB_PRECISE float t_31 = t_29 + 2.1212303638458252e-1;
    MOMENTLAB_PRECISE float t_32 = t_6 * t_31;
    MOMENTLAB_PRECISE float t_33 = t_32 - t_27;
    MOMENTLAB_PRECISE float t_35 = t_33 + 1.4546218514442444e-1;
    MOMENTLAB_PRECISE float t_36 = t_5 * t_35;
    MOMENTLAB_PRECISE float t_37 = t_36 - t_31;
    MOMENTLAB_PRECISE float t_39 = t_37 + 5.629452466964722e-1;
    MOMENTLAB_PRECISE float t_40 = clamp(t_39, 0e0, 1e0); // stored channel 1
    MOMENTLAB_PRECISE float t_42 = t_6 * (-5.198710039258003e-2);
    MOMENTLAB_PRECISE float t_44 = t_42 + (-1.2372007966041565e-1);
    MOMENTLAB_PRECISE float t_45 = t_6 * t_44;
    MOMENTLAB_PRECISE float t_46 = t_45 - (-5.198710039258003e-2);
    MOMENTLAB_PRECISE float t_48 = t_46 + 5.895322188735008e-2;
    MOMENTLAB_PRECISE float t_49 = t_6 * t_48;
    MOMENTLAB_PRECISE float t_50 = t_49 - t_44;
    MOMENTLAB_PRECISE float t_52 = t_50 + 5.704388618469238e-1;
    MOMENTLAB_PRECISE float t_53 = t_5 * t_52;
    MOMENTLAB_PRECISE float t_54 = t_53 - t_48;
    MOMENTLAB_PRECISE float t_56 = t_54 + 4.3975263833999634e-1;
    MOMENTLAB_PRECISE float t_57 = clamp(t_56, 0e0, 1e0); // stored channel 2
    MOMENTLAB_PRECISE float t_59 = t_6 * (-1.8728753924369812e-1);
    MOMENTLAB_PRECISE float t_61 = t_59 + 3.1250024790097086e-9;
    MOMENTLAB_PRECISE float t_62 = t_6 * t_61;
    MOMENTLAB_PRECISE float t_63 = t_62 - (-1.8728753924369812e-1);
    MOMENTLAB_PRECISE float t_65 = t_63 + (-4.7490060329437256e-1);
    MOMENTLAB_PRECISE float t_66 = t_6 * t_65;
    MOMENTLAB_PRECISE float t_67 = t_66 - t_61;
    MOMENTLAB_PRECISE float t_69 = t_67 + 2.1875003142213245e-8;
    MOMENTLAB_PRECISE float t_70 = t_5 * t_69;
    MOMENTLAB_PRECISE float t_71 = t_70 - t_65;
    MOMENTLAB_PRECISE float t_73 = t_71 + 6.621881723403931e-1;
    MOMENTLAB_PRECISE float t_74 = clamp(t_73, 0e0, 1e0); // stored channel 3
    s[0] = t_23;
    s[1] = t_40;
    s[2] = t_57;
    s[3] = t_74;
}

void decodeMoments4(float s[4], out float b[4])
{
    MOMENTLAB_PRECISE float t_5 = s[0] - 3.595588356256485e-2;
    MOMENTLAB_PRECISE float t_7 = 2.227744162082672e-1 * t_5;
    MOMENTLAB_PRECISE float t_9 = 7.719728350639343e-2 * s[1];
    MOMENTLAB_PRECISE float t_10 = t_7 + t_9;
    MOMENTLAB_PRECISE float t_12 = 7.926986813545227e-1 * s[2];
    MOMENTLAB_PRECISE float t_13 = t_10 + t_12;
    MOMENTLAB_PRECISE float t_15 = 3.194175660610199e-2 * s[3];
    MOMENTLAB_PRECISE float t_16 = t_13 + t_15;
    MOMENTLAB_PRECISE float t_18 = 1.5496793389320374e-1 * t_5;
    MOMENTLAB_PRECISE float t_20 = 1.3946294784545898e-1 * s[1];
    MOMENTLAB_PRECISE float t_21 = t_18 + t_20;
    MOMENTLAB_PRECISE float t_23 = 7.96341598033905e-1 * s[2];
    MOMENTLAB_PRECISE float t_24 = t_21 + t_23;
    MOMENTLAB_PRECISE float t_26 = (-1.7228232324123383e-1) * s[3];
    MOMENTLAB_PRECISE float t_27 = t_24 + t_26;
    MOMENTLAB_PRECISE float t_29 = 1.4519889652729034e-1 * t_5;
    MOMENTLAB_PRECISE float t_31 = 2.1202021837234497e-1 * s[1];
    MOMENTLAB_PRECISE float t_32 = t_29 + t_31;
    MOMENTLAB_PRECISE float t_34 = 7.258694767951965e-1 * s[2];
    MOMENTLAB_PRECISE float t_35 = t_32 + t_34;
    MOMENTLAB_PRECISE float t_37 = (-2.7580147981643677e-1) * s[3];
    MOMENTLAB_PRECISE float t_38 = t_35 + t_37;
    MOMENTLAB_PRECISE float t_40 = 1.6312745213508606e-1 * t_5;
    MOMENTLAB_PRECISE float t_42 = 2.5914323329925537e-1 * s[1];
    MOMENTLAB_PRECISE float t_43 = t_40 + t_42;
    MOMENTLAB_PRECISE float t_45 = 6.539092659950256e-1 * s[2];
    MOMENTLAB_PRECISE float t_46 = t_43 + t_45;
    MOMENTLAB_PRECISE float t_48 = (-3.3761316537857056e-1) * s[3];
    MOMENTLAB_PRECISE float t_49 = t_46 + t_48;
    b[0] = t_16;
    b[1] = t_27;
    b[2] = t_38;
    b[3] = t_49;
}

vec4 encodeMoments4Vec(float z)
{
    MOMENTLAB_PRECISE float t_4 = z * 2e0;
    MOMENTLAB_PRECISE float t_5 = t_4 - 1e0; // x = 2z - 1
    MOMENTLAB_PRECISE float t_6 = t_5 + t_5;
    MOMENTLAB_PRECISE float t_8 = t_6 * 3.075806796550751e-1;
    MOMENTLAB_PRECISE float t_10 = t_8 + 3.177993893623352e-1;
    MOMENTLAB_PRECISE float t_11 = t_6 * t_10;
    MOMENTLAB_PRECISE float t_12 = t_11 - 3.075806796550751e-1;
    MOMENTLAB_PRECISE float t_14 = t_12 + (-2.1518763899803162e-1);
    MOMENTLAB_PRECISE float t_15 = t_6 * t_14;
    MOMENTLAB_PRECISE float t_16 = t_15 - t_10;
    MOMENTLAB_PRECISE float t_18 = t_16 + 1.6422267258167267e-1;
    MOMENTLAB_PRECISE float t_19 = t_5 * t_18;
    MOMENTLAB_PRECISE float t_20 = t_19 - t_14;
    MOMENTLAB_PRECISE float t_22 = t_20 + 4.2558491230010986e-1;
    MOMENTLAB_PRECISE float t_23 = clamp(t_22, 0e0, 1e0); // stored channel 0
    MOMENTLAB_PRECISE float t_25 = t_6 * (-2.7628830075263977e-1);
    MOMENTLAB_PRECISE float t_27 = t_25 + 3.533177673816681e-1;
    MOMENTLAB_PRECISE float t_28 = t_6 * t_27;
    MOMENTLAB_PRECISE float t_29 = t_28 - (-2.7628830075263977e-1);
    MOMENTLAB_PRECISE float t_31 = t_29 + 2.1212303638458252e-1;
    MOMENTLAB_PRECISE float t_32 = t_6 * t_31;
    MOMENTLAB_PRECISE float t_33 = t_32 - t_27;
    MOMENTLAB_PRECISE float t_35 = t_33 + 1.4546218514442444e-1;
    MOMENTLAB_PRECISE float t_36 = t_5 * t_35;
    MOMENTLAB_PRECISE float t_37 = t_36 - t_31;
    MOMENTLAB_PRECISE float t_39 = t_37 + 5.629452466964722e-1;
    MOMENTLAB_PRECISE float t_40 = clamp(t_39, 0e0, 1e0); // stored channel 1
    MOMENTLAB_PRECISE float t_42 = t_6 * (-5.198710039258003e-2);
    MOMENTLAB_PRECISE float t_44 = t_42 + (-1.2372007966041565e-1);
    MOMENTLAB_PRECISE float t_45 = t_6 * t_44;
    MOMENTLAB_PRECISE float t_46 = t_45 - (-5.198710039258003e-2);
    MOMENTLAB_PRECISE float t_48 = t_46 + 5.895322188735008e-2;
    MOMENTLAB_PRECISE float t_49 = t_6 * t_48;
    MOMENTLAB_PRECISE float t_50 = t_49 - t_44;
    MOMENTLAB_PRECISE float t_52 = t_50 + 5.704388618469238e-1;
    MOMENTLAB_PRECISE float t_53 = t_5 * t_52;
    MOMENTLAB_PRECISE float t_54 = t_53 - t_48;
    MOMENTLAB_PRECISE float t_56 = t_54 + 4.3975263833999634e-1;
    MOMENTLAB_PRECISE float t_57 = clamp(t_56, 0e0, 1e0); // stored channel 2
    MOMENTLAB_PRECISE float t_59 = t_6 * (-1.8728753924369812e-1);
    MOMENTLAB_PRECISE float t_61 = t_59 + 3.1250024790097086e-9;
    MOMENTLAB_PRECISE float t_62 = t_6 * t_61;
    MOMENTLAB_PRECISE float t_63 = t_62 - (-1.8728753924369812e-1);
    MOMENTLAB_PRECISE float t_65 = t_63 + (-4.7490060329437256e-1);
    MOMENTLAB_PRECISE float t_66 = t_6 * t_65;
    MOMENTLAB_PRECISE float t_67 = t_66 - t_61;
    MOMENTLAB_PRECISE float t_69 = t_67 + 2.1875003142213245e-8;
    MOMENTLAB_PRECISE float t_70 = t_5 * t_69;
    MOMENTLAB_PRECISE float t_71 = t_70 - t_65;
    MOMENTLAB_PRECISE float t_73 = t_71 + 6.621881723403931e-1;
    MOMENTLAB_PRECISE float t_74 = clamp(t_73, 0e0, 1e0); // stored channel 3
    return vec4(t_23, t_40, t_57, t_74);
}

vec4 decodeMoments4Vec(vec4 s0123)
{
    MOMENTLAB_PRECISE float t_5 = s0123.x - 3.595588356256485e-2;
    MOMENTLAB_PRECISE float t_7 = 2.227744162082672e-1 * t_5;
    MOMENTLAB_PRECISE float t_9 = 7.719728350639343e-2 * s0123.y;
    MOMENTLAB_PRECISE float t_10 = t_7 + t_9;
    MOMENTLAB_PRECISE float t_12 = 7.926986813545227e-1 * s0123.z;
    MOMENTLAB_PRECISE float t_13 = t_10 + t_12;
    MOMENTLAB_PRECISE float t_15 = 3.194175660610199e-2 * s0123.w;
    MOMENTLAB_PRECISE float t_16 = t_13 + t_15;
    MOMENTLAB_PRECISE float t_18 = 1.5496793389320374e-1 * t_5;
    MOMENTLAB_PRECISE float t_20 = 1.3946294784545898e-1 * s0123.y;
    MOMENTLAB_PRECISE float t_21 = t_18 + t_20;
    MOMENTLAB_PRECISE float t_23 = 7.96341598033905e-1 * s0123.z;
    MOMENTLAB_PRECISE float t_24 = t_21 + t_23;
    MOMENTLAB_PRECISE float t_26 = (-1.7228232324123383e-1) * s0123.w;
    MOMENTLAB_PRECISE float t_27 = t_24 + t_26;
    MOMENTLAB_PRECISE float t_29 = 1.4519889652729034e-1 * t_5;
    MOMENTLAB_PRECISE float t_31 = 2.1202021837234497e-1 * s0123.y;
    MOMENTLAB_PRECISE float t_32 = t_29 + t_31;
    MOMENTLAB_PRECISE float t_34 = 7.258694767951965e-1 * s0123.z;
    MOMENTLAB_PRECISE float t_35 = t_32 + t_34;
    MOMENTLAB_PRECISE float t_37 = (-2.7580147981643677e-1) * s0123.w;
    MOMENTLAB_PRECISE float t_38 = t_35 + t_37;
    MOMENTLAB_PRECISE float t_40 = 1.6312745213508606e-1 * t_5;
    MOMENTLAB_PRECISE float t_42 = 2.5914323329925537e-1 * s0123.y;
    MOMENTLAB_PRECISE float t_43 = t_40 + t_42;
    MOMENTLAB_PRECISE float t_45 = 6.539092659950256e-1 * s0123.z;
    MOMENTLAB_PRECISE float t_46 = t_43 + t_45;
    MOMENTLAB_PRECISE float t_48 = (-3.3761316537857056e-1) * s0123.w;
    MOMENTLAB_PRECISE float t_49 = t_46 + t_48;
    return vec4(t_16, t_27, t_38, t_49);
}
