; TF5200 programming manual, "Indirect parameters": PP120 writes the parameter whose address P120 holds
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206884875.html
; adapted: the page's sentences as blocks; a #MSG and M30 appended.
; expect: msg "P10=123.456 P120=10"
N10 P120=10
N20 PP120=123.456
N30 #MSG ["P10=%.3f P120=%.0f", P10, P120]
N40 M30
