; TF5200 programming manual, "Reference point offset (G92)": selecting a reference point offset in G91 mode
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206145291.html
; adapted: M30 appended.
; expect: end X=0 Y=0
; expect: runs N20 1
N10 G92 X10 Y20
N20 G0 X0 G91       (may not cause any movement of the X axis)
N30 M30
