// The venue layer's logic, free of UnityEngine so that it runs on Mono in the host tests
// (tests/tests/unity_logic.rs): edge arrows from SitarSession.Guide, the kineticon that
// pulses each marker for its first seconds in view, and the colours of the venue map layer.
// The component that draws them is Components/SitarVenue.cs.
using System;

namespace Sitar
{
    /// <summary>An arrow at the screen's edge pointing to an off-screen target.</summary>
    public struct EdgeArrow
    {
        /// <summary>Index of the target in the Guide array (markers first, then venue cells).</summary>
        public int Index;
        /// <summary>Position in Unity's screen space (pixels, origin bottom-left, y up).</summary>
        public float X, Y;
        /// <summary>Rotation about the screen's normal for an arrow drawn pointing right
        /// (degrees, counter-clockwise as Unity's z rotation).</summary>
        public float RotationDeg;
        /// <summary>The target's distance from the camera (m).</summary>
        public float DistanceM;
    }

    /// <summary>
    /// A kineticon: each target pulses (its scale swings around 1) for its first
    /// <see cref="PulseSeconds"/> on screen, then keeps still; the clock starts the first time
    /// the target is seen. Allocation-free once it has room for every target.
    /// </summary>
    public sealed class Kineticon
    {
        public double PulseSeconds = 3.0;
        public double PulsesPerSecond = 1.5;
        public double Amplitude = 0.35;
        double[] firstSeen = new double[0];

        /// <summary>Forgets every target (e.g. after new results change the markers).</summary>
        public void Reset()
        {
            for (int i = 0; i < firstSeen.Length; i++) firstSeen[i] = double.NaN;
        }

        /// <summary>The scale of target <paramref name="index"/> at <paramref name="nowS"/>.</summary>
        public double Scale(int index, bool onScreen, double nowS)
        {
            if (index < 0) throw new ArgumentOutOfRangeException("index");
            if (index >= firstSeen.Length)
            {
                int old = firstSeen.Length;
                Array.Resize(ref firstSeen, Math.Max(index + 1, 2 * old));
                for (int i = old; i < firstSeen.Length; i++) firstSeen[i] = double.NaN;
            }
            if (double.IsNaN(firstSeen[index]))
            {
                if (!onScreen) return 1.0;
                firstSeen[index] = nowS;
            }
            double age = nowS - firstSeen[index];
            if (age < 0 || age >= PulseSeconds) return 1.0;
            // Fades out over the pulse time so the last swing ends at rest.
            double fade = 1.0 - age / PulseSeconds;
            return 1.0 + Amplitude * fade * Math.Abs(Math.Sin(Math.PI * PulsesPerSecond * age));
        }
    }

    /// <summary>Edge arrows and venue-layer colours.</summary>
    public static class VenueView
    {
        /// <summary>
        /// One arrow per off-screen entry of <paramref name="guides"/>[0, count) into
        /// <paramref name="arrows"/> (as many as fit); returns how many were written.
        /// SitarSession.Guide's pixels have the origin top-left, y down, and its angle is
        /// clockwise on screen; Unity's screen space has y up and turns counter-clockwise.
        /// </summary>
        public static int EdgeArrows(Guide[] guides, int count, int screenHeight, EdgeArrow[] arrows)
        {
            int n = 0;
            for (int i = 0; i < count && i < guides.Length && n < arrows.Length; i++)
            {
                Guide g = guides[i];
                if (g.OnScreen) continue;
                arrows[n++] = new EdgeArrow
                {
                    Index = i,
                    X = (float)g.XPx,
                    Y = (float)(screenHeight - g.YPx),
                    RotationDeg = (float)(-g.AngleRad * 180.0 / Math.PI),
                    DistanceM = (float)g.DistanceM,
                };
            }
            return n;
        }

        /// <summary>
        /// The colour (r, g, b, a in 0…1) a venue cell is drawn with: surface cells as
        /// translucent tiles in the class colours of the paper (blue low, yellow medium, red
        /// high, grey unknown), path cells as a faint trail of the same colours.
        /// </summary>
        public static void CellColor(CellKind kind, ErrorClass c, out float r, out float g, out float b, out float a)
        {
            switch (c)
            {
                case ErrorClass.Low: r = 0.15f; g = 0.35f; b = 0.95f; break;
                case ErrorClass.Medium: r = 1.00f; g = 0.85f; b = 0.10f; break;
                case ErrorClass.High: r = 0.90f; g = 0.10f; b = 0.10f; break;
                default: r = 0.60f; g = 0.60f; b = 0.60f; break;
            }
            a = kind == CellKind.Surface ? 0.45f : 0.15f;
        }
    }
}
