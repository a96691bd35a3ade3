; TF5200 programming manual, "Indirect parameters": P20 and P40 assigned 50
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206884875.html
; adapted: a #MSG of P20 and P40 and M30 appended to show the result.
; expect: msg "P20=50 P40=50"
N110 P1 = 20  P2 = 40
N120 PP1 = 50
N130 PP2 = PP1
N140 #MSG ["P20=%.0f P40=%.0f", P20, P40]
N150 M30
