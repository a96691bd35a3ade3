; TF5200 programming manual, "Global, valid throughout main program (V.S.)"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/207973899.html
; adapted: the page's ":" lines dropped; G01 F6000 before the move; M30 appended.
; expect: end X=20
#VAR
  V.S.VAR1                      ;REAL64, 0.0
  V.S.VAR2 : UNS32 = 200        ;UNS32, 200
  V.S.VAR3 : REAL64 = 11.34     ;REAL64, 11.34
  V.S.VAR4 : BOOLEAN            ;BOOLEAN, FALSE or 0
  V.S.VAR[5] = [5,10,10,15,20]  ;Array with REAL64 values
#ENDVAR
G01 F6000
XV.S.VAR[4]        ;X20.0
M30
