"""hprt's glossy material for Mitsuba 3: Lambertian diffuse plus a normalised Phong lobe.

f(wi, wo) = k_d/pi + k_s (s + 1)/(2 pi) cos^s(alpha) / cos(theta_o), alpha the angle between
wo and the mirror direction of wi, for directions above the surface (CONVENTIONS.md, "Glossy
materials"). Sampled as hprt's path tracer samples it: the cosine or the lobe, the lobe with
probability Y(k_s) / (Y(k_d) + Y(k_s)), the pdf their mixture. Mitsuba 3 has no Phong plugin.

Parameters: `reflectance` (k_d: rgb or texture), `specular` (k_s: rgb), `exponent` (s).
Use: import this file (`import phong`) after `mi.set_variant(...)`, before loading a scene
that names `hprtphong`. Written by `hprt export`.
"""

import drjit as dr
import mitsuba as mi


def luminance(c):
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


class HprtPhong(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.kd = props.get("reflectance", mi.ScalarColor3f(0.5))
        self.ks = mi.Color3f(props.get("specular", mi.ScalarColor3f(0.0)))
        self.s = mi.Float(props.get("exponent", 1.0))
        flags = (
            mi.BSDFFlags.DiffuseReflection
            | mi.BSDFFlags.GlossyReflection
            | mi.BSDFFlags.FrontSide
        )
        self.m_components = [flags]
        self.m_flags = flags

    def diffuse(self, si, active):
        if isinstance(self.kd, mi.Texture):
            return self.kd.eval(si, active)
        return mi.Color3f(self.kd)

    def lobe_probability(self, kd):
        d = dr.maximum(luminance(kd), 0.0)
        s = dr.maximum(luminance(self.ks), 0.0)
        return dr.select(d + s > 0.0, s / (d + s), 0.0)

    def lobe(self, cos_alpha):
        """D_s: (s + 1)/(2 pi) cos^s(alpha), zero past 90 degrees."""
        c = dr.maximum(cos_alpha, 0.0)
        return dr.select(cos_alpha > 0.0, (self.s + 1.0) * dr.inv_two_pi * dr.power(c, self.s), 0.0)

    @staticmethod
    def mirror(wi):
        return mi.Vector3f(-wi.x, -wi.y, wi.z)

    def eval_pdf(self, ctx, si, wo, active=True):
        cos_i = mi.Frame3f.cos_theta(si.wi)
        cos_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_i > 0.0) & (cos_o > 0.0)
        kd = self.diffuse(si, active)
        p = self.lobe_probability(kd)
        lobe = self.lobe(dr.dot(self.mirror(si.wi), wo))
        value = kd * (cos_o * dr.inv_pi) + self.ks * lobe
        pdf = (1.0 - p) * cos_o * dr.inv_pi + p * lobe
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def eval(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[0]

    def pdf(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[1]

    def sample(self, ctx, si, sample1, sample2, active=True):
        cos_i = mi.Frame3f.cos_theta(si.wi)
        active = active & (cos_i > 0.0)
        kd = self.diffuse(si, active)
        p = self.lobe_probability(kd)
        pick_lobe = sample1 < p
        # The lobe around the mirror direction: cos(alpha) = u^(1/(s+1)).
        cos_a = dr.power(sample2.x, 1.0 / (self.s + 1.0))
        sin_a = dr.safe_sqrt(1.0 - cos_a * cos_a)
        phi = dr.two_pi * sample2.y
        local = mi.Vector3f(sin_a * dr.cos(phi), sin_a * dr.sin(phi), cos_a)
        lobe_dir = mi.Frame3f(self.mirror(si.wi)).to_world(local)
        cosine_dir = mi.warp.square_to_cosine_hemisphere(sample2)
        wo = dr.select(pick_lobe, lobe_dir, cosine_dir)
        value, pdf = self.eval_pdf(ctx, si, wo, active)
        active = active & (pdf > 0.0)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = wo
        bs.pdf = pdf
        bs.eta = 1.0
        bs.sampled_component = 0
        bs.sampled_type = mi.UInt32(
            dr.select(pick_lobe, +mi.BSDFFlags.GlossyReflection, +mi.BSDFFlags.DiffuseReflection)
        )
        return bs, dr.select(active, value / dr.maximum(pdf, 1e-20), 0.0)

    def traverse(self, callback):
        pass

    def to_string(self):
        return "HprtPhong[]"


mi.register_bsdf("hprtphong", lambda props: HprtPhong(props))
