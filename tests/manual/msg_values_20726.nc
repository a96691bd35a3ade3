; TF5200 diagnosis, ID 20726 "After a comma a mathematical expression is expected.": the syntax example
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/252347275.html
; adapted: M30 appended.
; expect: msg "WERT=10"
; expect: msg "WERT1=10 WERT2=20"
N10 #MSG ["WERT=%D", 10]
N20 #MSG ["WERT1=%D WERT2=%D", 10, 20]
N30 M30
