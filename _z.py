import sys

from devkit import session


def main(argv):
    session.load_penumbra().register()
    from devkit import reference_kit as kit

    for name in argv[1].split(","):
        ref = kit.cycles_reference(name, 128, 128, 72)
        vis = kit.measure_visibility(kit.build(name, 128, 72), "PENUMBRA", shadow_filter="PCSS")
        c = kit.compare(vis, ref)
        print(f"RES {name} {c['iou']:.4f} / {c['mae']:.4f}  pen {c['mae_penumbra']:.3f}", flush=True)
        if name == "contact":
            print("RES widths", kit.contact_widths(kit.build("contact", 128, 72), vis))


session.run(main, sys.argv)
