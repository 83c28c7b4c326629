// Stubs of the uGUI API (com.unity.ugui 1.0) used by unity-plugin/Runtime.
// They exist only to type-check the package with `mcs` against the real
// API's shapes (tests/tests/unity_package.rs); nothing here runs.
using UnityEngine.Events;

namespace UnityEngine.EventSystems
{
    public abstract class UIBehaviour : MonoBehaviour { }
}

namespace UnityEngine.UI
{
    public class Selectable : EventSystems.UIBehaviour { }

    public class Button : Selectable
    {
        public class ButtonClickedEvent : UnityEvent { }

        public ButtonClickedEvent onClick { get { throw null; } set { throw null; } }
    }

    public abstract class Graphic : EventSystems.UIBehaviour { }

    public abstract class MaskableGraphic : Graphic { }

    public class RawImage : MaskableGraphic
    {
        public Texture texture { get { throw null; } set { throw null; } }
    }

    public class Text : MaskableGraphic
    {
        public virtual string text { get { throw null; } set { throw null; } }
    }
}
