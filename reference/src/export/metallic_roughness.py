"""glTF 2.0's metallic-roughness material for Mitsuba 3, as hprt draws it (the specification's
Appendix B; CONVENTIONS.md, "Metallic-roughness materials").

f = (1 - F) c_diff / pi + F D V, with c_diff = (1 - metallic) base, F Schlick's Fresnel at v.h
from F0 = lerp(0.04, base, metallic), D GGX with alpha = roughness^2 and V Smith's
height-correlated visibility. Mitsuba 3's own microfacet BSDFs use a separable Smith term and
no such mix, so this plugin evaluates the formula itself; it samples the cosine or GGX's
visible normals (Mitsuba's own sampler), half each, the pdf their mixture.

Parameters: `reflectance` (the base colour: rgb or texture), `metallic`, `roughness` (floats).
Use: import this file (`import metallic_roughness`) after `mi.set_variant(...)`, before
loading a scene that names `hprtmetallicroughness`. Written by `hprt export`.
"""

import drjit as dr
import mitsuba as mi

DIELECTRIC_F0 = 0.04
MIN_ALPHA = 1e-3


class HprtMetallicRoughness(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.base = props.get("reflectance", mi.ScalarColor3f(0.5))
        self.metallic = mi.Float(props.get("metallic", 1.0))
        roughness = props.get("roughness", 1.0)
        self.alpha = max(roughness * roughness, MIN_ALPHA)
        self.distribution = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)
        flags = (
            mi.BSDFFlags.DiffuseReflection
            | mi.BSDFFlags.GlossyReflection
            | mi.BSDFFlags.FrontSide
        )
        self.m_components = [flags]
        self.m_flags = flags

    def base_color(self, si, active):
        if isinstance(self.base, mi.Texture):
            return self.base.eval(si, active)
        return mi.Color3f(self.base)

    def visibility(self, cos_l, cos_v):
        a2 = self.alpha * self.alpha
        gv = cos_l * dr.sqrt(cos_v * cos_v * (1.0 - a2) + a2)
        gl = cos_v * dr.sqrt(cos_l * cos_l * (1.0 - a2) + a2)
        return 0.5 / dr.maximum(gv + gl, 1e-20)

    def eval_pdf(self, ctx, si, wo, active=True):
        cos_v = mi.Frame3f.cos_theta(si.wi)
        cos_l = mi.Frame3f.cos_theta(wo)
        active = active & (cos_v > 0.0) & (cos_l > 0.0)
        base = self.base_color(si, active)
        h = dr.normalize(si.wi + wo)
        vh = dr.dot(si.wi, h)
        f0 = DIELECTRIC_F0 * (1.0 - self.metallic) + base * self.metallic
        fresnel = f0 + (1.0 - f0) * dr.power(1.0 - dr.clip(vh, 0.0, 1.0), 5.0)
        d = self.distribution.eval(h)
        diffuse = (1.0 - fresnel) * base * (1.0 - self.metallic) * dr.inv_pi
        value = (diffuse + fresnel * d * self.visibility(cos_l, cos_v)) * cos_l
        specular_pdf = dr.select(
            vh > 0.0, self.distribution.pdf(si.wi, h) / (4.0 * dr.abs(dr.dot(wo, h))), 0.0
        )
        pdf = 0.5 * cos_l * dr.inv_pi + 0.5 * specular_pdf
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def eval(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[0]

    def pdf(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[1]

    def sample(self, ctx, si, sample1, sample2, active=True):
        active = active & (mi.Frame3f.cos_theta(si.wi) > 0.0)
        pick_specular = sample1 < 0.5
        m, _ = self.distribution.sample(si.wi, sample2)
        specular_dir = mi.reflect(si.wi, m)
        cosine_dir = mi.warp.square_to_cosine_hemisphere(sample2)
        wo = dr.select(pick_specular, specular_dir, cosine_dir)
        value, pdf = self.eval_pdf(ctx, si, wo, active)
        active = active & (pdf > 0.0)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = wo
        bs.pdf = pdf
        bs.eta = 1.0
        bs.sampled_component = 0
        bs.sampled_type = mi.UInt32(
            dr.select(
                pick_specular, +mi.BSDFFlags.GlossyReflection, +mi.BSDFFlags.DiffuseReflection
            )
        )
        return bs, dr.select(active, value / dr.maximum(pdf, 1e-20), 0.0)

    def traverse(self, callback):
        pass

    def to_string(self):
        return "HprtMetallicRoughness[]"


mi.register_bsdf("hprtmetallicroughness", lambda props: HprtMetallicRoughness(props))
