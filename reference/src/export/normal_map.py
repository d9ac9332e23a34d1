"""glTF 2.0's tangent-space normal maps for Mitsuba 3, as hprt draws them (CONVENTIONS.md,
"Normal maps").

The shading normal is normalize(t m.x + b m.y + n m.z) with m = 2 texel - 1 (the map's scale
is folded into the exported texels), n the interpolated vertex normal, t the interpolated
tangent made orthogonal to n and b = cross(n, t) times the bitangent's sign. The tangents and
signs are hprt's (from the glTF file, or MikkTSpace), read from the mesh's `vertex_tangent` and
`vertex_handed` attributes: Mitsuba's own `normalmap` builds its frame from dp/du alone, which
turns the bumps of mirrored texture coordinates inside out.

Parameters: `normalmap` (a raw bitmap texture) and one nested BSDF.
Use: import this file (`import normal_map`) after `mi.set_variant(...)`, before loading a
scene that names `hprtnormalmap`. Written by `hprt export`.
"""

import drjit as dr
import mitsuba as mi


class HprtNormalMap(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        inner = [obj for _, obj in props.objects() if isinstance(obj, mi.BSDF)]
        if len(inner) != 1:
            raise ValueError("hprtnormalmap wraps exactly one BSDF")
        self.inner = inner[0]
        self.normalmap = props.get("normalmap")
        self.m_components = [self.inner.flags()]
        self.m_flags = self.inner.flags()

    def perturbed(self, si, active):
        """The interaction with its shading frame turned to the mapped normal."""
        n = si.sh_frame.n
        tangent = si.shape.eval_attribute_3("vertex_tangent", si, active)
        handed = si.shape.eval_attribute_1("vertex_handed", si, active)
        t = mi.Vector3f(tangent[0], tangent[1], tangent[2])
        t = t - n * dr.dot(n, t)
        length2 = dr.squared_norm(t)
        t = t * dr.rsqrt(dr.maximum(length2, 1e-24))
        b = dr.cross(n, t) * dr.select(handed < 0.0, -1.0, 1.0)
        texel = self.normalmap.eval(si, active)
        m = mi.Vector3f(texel[0], texel[1], texel[2]) * 2.0 - 1.0
        mapped = t * m.x + b * m.y + n * m.z
        mapped_length2 = dr.squared_norm(mapped)
        ok = (length2 > 1e-12) & (mapped_length2 > 1e-12)
        normal = dr.select(ok, mapped * dr.rsqrt(dr.maximum(mapped_length2, 1e-24)), n)
        out = mi.SurfaceInteraction3f(si)
        out.sh_frame = mi.Frame3f(normal)
        out.wi = out.to_local(si.to_world(si.wi))
        return out

    def sample(self, ctx, si, sample1, sample2, active=True):
        p = self.perturbed(si, active)
        bs, weight = self.inner.sample(ctx, p, sample1, sample2, active)
        bs.wo = si.to_local(p.to_world(bs.wo))
        return bs, weight

    def eval(self, ctx, si, wo, active=True):
        p = self.perturbed(si, active)
        return self.inner.eval(ctx, p, p.to_local(si.to_world(wo)), active)

    def pdf(self, ctx, si, wo, active=True):
        p = self.perturbed(si, active)
        return self.inner.pdf(ctx, p, p.to_local(si.to_world(wo)), active)

    def eval_pdf(self, ctx, si, wo, active=True):
        p = self.perturbed(si, active)
        return self.inner.eval_pdf(ctx, p, p.to_local(si.to_world(wo)), active)

    def traverse(self, callback):
        self.inner.traverse(callback)

    def to_string(self):
        return f"HprtNormalMap[{self.inner}]"


mi.register_bsdf("hprtnormalmap", lambda props: HprtNormalMap(props))
