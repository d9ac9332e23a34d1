"""hprt's surfaces for Mitsuba 3: both sides of a triangle show the radiance of its front.

hprt's bake, reference and renderer treat every triangle as a thin sheet whose back shows what
its front shows (CONVENTIONS.md, "Surfaces"). Mitsuba's `twosided` shades the back as a surface
of its own, facing the other way, so the two differ wherever a back face is seen (the inside of
the teapot's rim, the tip of its spout). `thinsheet` wraps one BSDF and mirrors a viewing
direction that arrives from the back onto the front: light then leaves toward a viewer on either
side as it leaves the front, and the wrapped BSDF scatters into the front's hemisphere only.

Use: import this file (`import thinsheet`) after `mi.set_variant(...)`, then
`mi.load_file("scene.xml", surface="thinsheet")`. Written by `hprt export`.
"""

import drjit as dr
import mitsuba as mi


class ThinSheet(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        inner = [obj for _, obj in props.objects() if isinstance(obj, mi.BSDF)]
        if len(inner) != 1:
            raise ValueError("thinsheet wraps exactly one BSDF")
        self.inner = inner[0]
        flags = self.inner.flags() | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
        self.m_components = [flags]
        self.m_flags = flags

    @staticmethod
    def front(si):
        """The interaction seen from the front: the viewing direction mirrored if behind."""
        mirrored = mi.SurfaceInteraction3f(si)
        mirrored.wi = mi.Vector3f(si.wi.x, si.wi.y, dr.abs(si.wi.z))
        return mirrored

    def sample(self, ctx, si, sample1, sample2, active=True):
        return self.inner.sample(ctx, self.front(si), sample1, sample2, active)

    def eval(self, ctx, si, wo, active=True):
        return self.inner.eval(ctx, self.front(si), wo, active)

    def pdf(self, ctx, si, wo, active=True):
        return self.inner.pdf(ctx, self.front(si), wo, active)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.inner.eval_pdf(ctx, self.front(si), wo, active)

    def traverse(self, callback):
        self.inner.traverse(callback)

    def to_string(self):
        return f"ThinSheet[{self.inner}]"


mi.register_bsdf("thinsheet", lambda props: ThinSheet(props))
